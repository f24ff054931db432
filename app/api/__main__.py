"""``python -m frictex``: the ``frictex`` command."""

from frictex.app.commands.entry import entry

entry()
