"""The five HRI services, their shared Zenoh runtime and the `hri` command."""
