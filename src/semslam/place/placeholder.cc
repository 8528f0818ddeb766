// Placeholder until the place module has sources.
