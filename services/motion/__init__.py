"""The motion service (DESIGN.md, Processes)."""
