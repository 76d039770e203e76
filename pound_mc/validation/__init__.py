"""Validation cases: pound-mc against independent references."""
