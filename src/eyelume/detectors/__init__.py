"""Detectors: the sensor model (irradiance → electrons → digital counts)."""
