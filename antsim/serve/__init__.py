"""`antsim serve`: the simulated antenna of a scenario as a KATCP device (see docs/katcp.md)."""
