"""Tests of antsim.simulate, a file per module: the engines every feature shares."""
