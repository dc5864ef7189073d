"""The `mocap` command (`main`), one module per subcommand, and the module entry points
(`python -m mocap.cli.fetch_data`). The only room that prints."""

from mocap.cli.main import build_parser, main

__all__ = ["build_parser", "main"]
