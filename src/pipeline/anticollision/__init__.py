"""Anti-collision: closest approach between wells and the ISCWSA separation factor."""
