"""frictex entry points: the ``frictex`` command, replay, reports, the demo."""
