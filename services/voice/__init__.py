"""The voice service (DESIGN.md, Processes)."""
