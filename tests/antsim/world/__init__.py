"""Tests of antsim.world: the simulated telescope, one file per module."""
