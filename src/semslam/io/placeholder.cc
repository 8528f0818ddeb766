// Replaced as the io module is implemented.
