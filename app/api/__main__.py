"""``python -m frictex``: the ``frictex`` command."""

from frictex.app.commands.cli import entry

entry()
