"""Seeing runs: video, figures, the live viewer."""
