// Placeholder until the map module has sources.
