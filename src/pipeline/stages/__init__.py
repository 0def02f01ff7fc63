"""Built-in stages (each module is a plugin registered through the hooks)."""
