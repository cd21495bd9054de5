"""Planning: rest-to-rest moves on the flat outputs and their feasibility."""
