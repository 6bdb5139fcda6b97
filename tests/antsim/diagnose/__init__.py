"""Tests of antsim.diagnose, a file per module."""
