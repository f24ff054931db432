"""The bounds of a run's settings, shared by the command line (``app.commands.argtypes``)
and batch manifests (``app.engine.batch``), so that a manifest accepts exactly what the
command line does."""

#: output rate of the haptic pipeline, Hz (inclusive)
OUTPUT_RATES_HZ = (100.0, 1e6)
#: output samples per block (inclusive)
BLOCK_SIZES = (1, 100_000)
