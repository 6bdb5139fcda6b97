"""Tests of antsim/simulate, a file per module."""
