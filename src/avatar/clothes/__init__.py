"""clothes."""
