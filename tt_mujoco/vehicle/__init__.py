"""The vehicle: parameters, MJCF/URDF generation, the reduced model, steering gains."""
