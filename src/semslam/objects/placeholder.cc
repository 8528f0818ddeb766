// Placeholder until the objects module has sources.
