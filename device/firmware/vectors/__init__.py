"""The protocol test vectors shared by the Python simulated device and the C firmware."""
