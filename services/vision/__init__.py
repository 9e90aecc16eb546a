"""The vision service (DESIGN.md, Processes)."""
