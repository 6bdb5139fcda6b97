"""Tests of antsim.serve."""
