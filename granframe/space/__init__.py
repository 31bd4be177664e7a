"""Space-inhomogeneous granular gases in one space dimension (docs/space.md)."""
