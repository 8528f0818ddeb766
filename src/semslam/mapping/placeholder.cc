// Placeholder until the mapping module has sources.
