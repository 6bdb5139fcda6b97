"""Tests of controller.program."""
