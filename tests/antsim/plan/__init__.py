"""Tests of antsim/plan, a file per module."""
