// Placeholder until the loop module has sources.
