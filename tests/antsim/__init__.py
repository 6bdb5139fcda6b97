"""Tests of antsim."""
