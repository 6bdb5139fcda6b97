"""Tests of antsim.figures, a file per module."""
