"""Exceptions and warnings raised by granframe.

Invalid user input always raises :class:`ValueError` or :class:`TypeError`
(built-in types, so callers need not import granframe to catch them); the
subclasses below only add context for plugin problems.
"""


class PluginError(ValueError):
    """A plugin could not be loaded, or two plugins claim the same name."""


class UnknownNameError(ValueError):
    """A registry was asked for a name nobody registered."""


class UnknownParameterError(TypeError):
    """A registered implementation was given a parameter its factory does not take."""


class BackendUnavailableError(ValueError):
    """An array backend whose package or device this machine lacks.

    The description naming it is still valid (its parameters were checked): a store
    written with it can be read here, and only building a run with it fails.
    """


class NonFiniteError(ValueError):
    """An operator was given an f with NaN or Inf (in a run: a step that blew up)."""


class AliasingWarning(UserWarning):
    """A velocity grid was built below the anti-aliasing bound on explicit request."""
