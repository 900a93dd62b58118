"""Attack scenarios, Monte Carlo simulation and metrics."""
