"""Observer gains and observer designs."""
