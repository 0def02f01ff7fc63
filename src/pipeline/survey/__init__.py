"""Survey geometry: minimum-curvature integration of inclination/azimuth surveys."""
