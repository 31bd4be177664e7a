"""Time stepping: the registered integrators (fixed and adaptive) and their stability limits."""
