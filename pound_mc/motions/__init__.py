"""motions."""
