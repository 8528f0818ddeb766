// Placeholder until the landmarks module has sources.
