"""Tests of controller.pointing."""
