"""Equations of motion: the space-homogeneous Boltzmann equation and its self-similar
rescaling."""
