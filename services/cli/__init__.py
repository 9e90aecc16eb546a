"""The `hri` command: launcher, demo and probing tools."""
