"""Tests of antsim/run."""
