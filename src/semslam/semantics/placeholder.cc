// Placeholder until the semantics module has sources.
