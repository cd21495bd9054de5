"""The sampled drive loop around a controller: drive (power stage), sensors, observers, the reference loop."""
