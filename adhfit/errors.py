"""Exceptions raised by adhfit.

Every exception subclasses an ordinary Python error so callers can catch either the adhfit type
or the built-in one, and carries the data needed to act on it.
"""
from __future__ import annotations

from typing import Any

#: Longest echo of a value in an error message, in characters (a 1 MB cell must not fill a terminal).
ECHO_LIMIT = 80


def clip(text: str, limit: int = ECHO_LIMIT) -> str:
    """``text`` cut to about ``limit`` characters for a message, saying how long it was.

    Examples
    --------
    >>> clip("Load (N)")
    'Load (N)'
    >>> clip("a" * 1000, limit=10)
    'aaaaaaaaa… (1000 characters)'
    """
    text = str(text)
    return text if len(text) <= limit else text[: max(limit - 1, 1)] + f"… ({len(text)} characters)"


def shown(value: Any, limit: int = ECHO_LIMIT) -> str:
    """``repr(value)`` for an error message, cut to about ``limit`` characters.

    Every message that echoes a user's value (a cell, a unit, a header, a scene value) goes through
    this, so a hostile or mistaken megabyte of text is named, not printed.

    Examples
    --------
    >>> shown("kPa")
    "'kPa'"
    >>> shown("x" * 1000, limit=20)
    "'xxxxxxxxxxxxxxxxx…' (1000 characters)"
    """
    try:
        text = repr(value)
    except RecursionError:  # a 1,000-deep table from a TOML file
        return f"<a {type(value).__name__} nested too deeply to show>"
    if len(text) <= limit:
        return text
    size = f" ({len(value)} characters)" if isinstance(value, (str, bytes)) else ""
    return text[: max(limit - 2, 1)] + "…" + text[0] * (text[0] in "'\"") + size



class AdhfitError(Exception):
    """Base class of every error adhfit raises on purpose."""


class InputError(AdhfitError, ValueError):
    """A parameter is outside its valid range.

    Parameters
    ----------
    name : str
        Parameter name as the user wrote it (keyword or CLI option).
    value : Any
        The offending value.
    valid : str
        Human-readable description of the valid range, e.g. ``"a float in (0, 1)"``.
    reason : str, optional
        Extra explanation (e.g. the cross-parameter constraint that failed).
    """

    def __init__(self, name: str, value: Any, valid: str, reason: str = "") -> None:
        self.name = name
        self.value = value
        self.valid = valid
        self.reason = reason
        msg = f"The '{name}' parameter must be {valid}. Got {shown(value)} instead."
        if reason:
            msg += f" {reason}"
        super().__init__(msg)


class ConvergenceError(AdhfitError, RuntimeError):
    """A root solve or continuation failed; carries the inputs that made it fail.

    Parameters
    ----------
    what : str
        Which solve failed (e.g. ``"no-slip pinning: C2 for given alpha"``).
    inputs : dict
        The dimensionless inputs of the failed solve.
    """

    def __init__(self, what: str, inputs: dict[str, Any] | None = None) -> None:
        self.what = what
        self.inputs = dict(inputs or {})
        detail = ", ".join(f"{k}={v!r}" for k, v in self.inputs.items())
        super().__init__(f"{what} did not converge" + (f" ({detail})" if detail else ""))


class DomainError(ConvergenceError):
    """No solution exists here: the scene (or a state it asks for) lies beyond a proven end of the model.

    Raised only where the end is proven -- an analytic bound, the branch's own end found along it,
    or failures that other row grids and the engine's own states agree on -- and never for a solver
    that merely failed (that is :class:`ConvergenceError`). The message states the bound in words
    and numbers and closes with what to change, never with "did not converge".

    It subclasses :class:`ConvergenceError` so that every existing ``except ConvergenceError``
    (retries on another row grid, the fit's "no history at these values") still catches it; catch
    ``DomainError`` first to tell "no solution exists" from "the solver failed". The command line
    exits with its own status (``EXIT_DOMAIN`` = 4, docs/contracts.md "Errors and exit statuses").

    Parameters
    ----------
    what : str
        Which end of the model the scene passes, e.g. ``"free membrane past vertical at the clamp"``.
    bound : str
        The bound in words and numbers, e.g. ``"a_max <= 0.4132 (the largest Case I contact radius)"``.
    fix : str
        What to change, e.g. ``"lower a_max or |p|"``.
    inputs : dict, optional
        The dimensionless inputs of the scene.
    """

    def __init__(self, what: str, bound: str = "", fix: str = "",
                 inputs: dict[str, Any] | None = None) -> None:
        self.what = what
        self.bound = bound
        self.fix = fix
        self.inputs = dict(inputs or {})
        detail = ", ".join(f"{k}={v!r}" for k, v in self.inputs.items())
        msg = f"no solution exists: {what}"
        if bound:
            msg += f"; {bound}"
        if fix:
            msg += f"; {fix}"
        if detail:
            msg += f" ({detail})"
        # bypass ConvergenceError's wording ("did not converge"): this is not a solver failure
        RuntimeError.__init__(self, msg)


class DataError(AdhfitError, ValueError):
    """A data or scene file cannot be used as given.

    Parameters
    ----------
    message : str
        What is wrong, in one line.
    path : str, optional
        File concerned.
    column : str, optional
        Column concerned.
    line : int, optional
        1-based line number in the file (header is line 1).
    """

    def __init__(self, message: str, *, path: str | None = None, column: str | None = None,
                 line: int | None = None) -> None:
        self.path = path
        self.column = column
        self.line = line
        where = []
        if path is not None:
            where.append(str(path))
        if line is not None:
            where.append(f"line {line}")
        if column is not None:
            where.append(f"column '{clip(column)}'")
        prefix = (", ".join(where) + ": ") if where else ""
        super().__init__(prefix + message)
