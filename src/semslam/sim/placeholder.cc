// Replaced as the sim module is implemented.
