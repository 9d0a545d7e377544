"""Helpers for verifying dnasim against independent codes (dev dependencies only)."""
