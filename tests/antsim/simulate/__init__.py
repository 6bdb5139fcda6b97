"""Tests of antsim.simulate: the engines every feature shares."""
