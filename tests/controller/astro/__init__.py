"""Tests of controller.astro."""
