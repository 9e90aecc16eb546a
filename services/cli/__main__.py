"""`python -m services.cli` is the `hri` command."""

from services.cli.main import app

app(prog_name="hri")
