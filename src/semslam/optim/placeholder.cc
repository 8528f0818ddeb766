// Placeholder until the optim module has sources.
