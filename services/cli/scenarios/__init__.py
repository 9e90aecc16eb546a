"""Built-in demo scenarios (YAML)."""
