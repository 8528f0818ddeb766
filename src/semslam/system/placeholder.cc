// Placeholder until the system module has sources.
