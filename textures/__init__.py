"""The texture file format, its validated scene model and the bundled library."""
