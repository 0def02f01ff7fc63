"""Earth references: rotation rate, normal gravity, frames (NED navigation, tool body)."""
