"""Finger tracking, the SHO / SHT / hybrid renderers, composition, the friction model and the visual layer."""
