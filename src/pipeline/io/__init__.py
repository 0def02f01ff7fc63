"""Built-in readers and writers (each module is a plugin registered through the hooks)."""
