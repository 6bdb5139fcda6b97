"""Tests of antsim.diagnose."""
