"""The ship domain on the co-simulation engine, in wings by role, lowest first: ship, weather,
routing, voyage, navigation, encounters, control; cosim registers them with the engine."""
