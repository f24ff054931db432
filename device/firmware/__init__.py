"""The reference firmware: its C sources, build and the host-side bindings to them."""
