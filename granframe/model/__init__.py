"""The physical model: collision kernels, restitution laws, initial data and the exact laws
that validate them."""
