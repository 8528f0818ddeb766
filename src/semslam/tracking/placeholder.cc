// Placeholder until the tracking module has sources.
