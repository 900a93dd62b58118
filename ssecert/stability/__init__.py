"""Stability certificates: Lyapunov, LMIs for the sparse observers, thesis assumptions."""
