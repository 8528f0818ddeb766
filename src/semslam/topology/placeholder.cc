// Placeholder until the topology module has sources.
