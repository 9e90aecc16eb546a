"""The reasoner service (DESIGN.md, Processes)."""
