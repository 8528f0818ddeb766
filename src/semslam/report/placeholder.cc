// Placeholder until the report module has sources.
