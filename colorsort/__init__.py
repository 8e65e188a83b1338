"""ColorSort."""
