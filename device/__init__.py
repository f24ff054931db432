"""The hardware side: structures and modes, actuation, the serial link and the simulated device."""
