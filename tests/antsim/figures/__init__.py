"""Tests of antsim/figures."""
