"""A run: its description (TOML), the runner that steps it, the zarr store it writes, and
sweeps of many runs."""
