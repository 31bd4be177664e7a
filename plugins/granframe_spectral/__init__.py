"""Spectral collision operators: direct (Filbet-Pareschi-Toscani) and fast (Hu-Ma).

A plugin shipped with granframe, registered through the public hook like any
third-party plugin (entry point ``spectral`` of the ``granframe`` group).
"""

from granframe import hookimpl

from granframe_spectral.direct import DirectSpectral
from granframe_spectral.fast import FastSpectral


@hookimpl
def granframe_register_collision_operators(registry):
    registry.add("fast_spectral", FastSpectral,
                 description="fast Fourier spectral method of Hu-Ma, O(M N_rho N^d log N)")
    registry.add("direct_spectral", DirectSpectral,
                 description="direct Fourier-Galerkin method of Filbet-Pareschi-Toscani, O(N^2d)")


__all__ = ["DirectSpectral", "FastSpectral"]
