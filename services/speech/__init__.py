"""The speech service (DESIGN.md, Processes)."""
