"""Tests of controller.scans: scans, their reduction, tipping and gain curves."""
