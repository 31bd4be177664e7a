"""What the checks of every family share: a failed condition raised as an
:class:`AssertionError` with its message, and the family's declared contract
(:mod:`granframe.contract_checks`) checked as part of the kit.
"""

from __future__ import annotations

from granframe import contract_checks


def require(condition, message: str) -> None:
    """Raise an AssertionError with ``message`` unless ``condition`` holds."""
    if not condition:
        raise AssertionError(message)


def require_contract(family: str, product) -> None:
    """The declared contract of ``family`` (:func:`granframe.contract_checks.check_product`)
    on ``product``, a violation raised as an AssertionError naming its class."""
    try:
        contract_checks.check_product(family, product)
    except contract_checks.ContractViolation as exc:
        raise AssertionError(f"{type(product).__name__}: {exc}") from None
