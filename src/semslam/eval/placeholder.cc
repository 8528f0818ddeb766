// Replaced as the eval module is implemented.
