"""The sections of a texture file, each checked by its own module against the key tables
of ``textures.keys``: ``device`` ([display] and [device] with its sub-tables),
``geometry`` (regions and what must lie on the display), ``layers`` ([[layer]]: the keys
every layer takes, then one builder per type from ``shapes``, ``forces`` and
``dynamic``), ``files`` (the files a texture names, confined to its folder)."""
