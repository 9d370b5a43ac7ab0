"""The kinengine exception hierarchy.

Every error kinengine raises derives from :class:`KinematicsError`; each
subclass also derives from the builtin a caller would naturally catch
(``ValueError`` for bad values, ``KeyError`` for unknown names).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
import difflib


class KinematicsError(Exception):
    """Base class of every kinengine error."""


class URDFError(KinematicsError, ValueError):
    """A robot description is missing, unreadable, malformed or unsupported.

    ``source`` names the file (or ``"<string>"``), ``element`` the offending
    element (e.g. ``"joint 'elbow'"``) and ``line`` its line number when known.
    """

    def __init__(self, message: str, *, source: str | None = None,
                 element: str | None = None, line: int | None = None) -> None:
        self.source = source
        self.element = element
        self.line = line
        where = []
        if source:
            where.append(f"{source}" + (f":{line}" if line else ""))
        if element:
            where.append(element)
        prefix = ", ".join(where)
        super().__init__(f"{prefix}: {message}" if prefix else message)


class FrameNotFoundError(KinematicsError, KeyError):
    """A frame (or joint) name is not part of the model.

    The message suggests the closest known names.
    """

    def __init__(self, name: object, known: Iterable[str], *, kind: str = "frame") -> None:
        self.name = name
        self.known = list(known)
        close = difflib.get_close_matches(str(name), self.known, n=3, cutoff=0.5)
        hint = (f" Did you mean {', '.join(repr(c) for c in close)}?" if close
                else f" Known {kind}s: {', '.join(self.known[:12])}"
                + (", ..." if len(self.known) > 12 else "") + ".")
        self.message = f"unknown {kind} {name!r}.{hint}"
        super().__init__(self.message)

    def __str__(self) -> str:  # KeyError would print the repr of the message
        return self.message


class ConfigurationError(KinematicsError, ValueError):
    """A joint configuration q (or velocity q̇, or a Jacobian handed in) has the wrong shape, type or values,
    or (``check_limits=True``) a joint outside its limits."""


class OptionError(KinematicsError, ValueError):
    """A keyword option out of its range (e.g. a negative iteration count) or a task without frames."""


class ParameterizationError(KinematicsError, ValueError):
    """An unknown parameterization name or an invalid parameter vector."""

    @classmethod
    def unknown(cls, kind: str, name: object, valid: Sequence[str]) -> "ParameterizationError":
        return cls(f"unknown {kind} parameterization {name!r}; valid names: {', '.join(valid)}")


class RepresentationSingularityError(KinematicsError, ValueError):
    """The pose parameterization is singular (E_e(χ) has no finite value) here.

    This is a property of the chosen coordinates χ, not of the robot: another
    parameterization (``alternatives``) is regular at the same pose.
    """

    def __init__(self, parameterization: str, distance: float, threshold: float,
                 alternatives: Sequence[str], detail: str = "") -> None:
        self.parameterization = parameterization
        self.distance = distance
        self.threshold = threshold
        self.alternatives = list(alternatives)
        msg = (f"{parameterization!r} is at a representation singularity "
               f"(distance {distance:.3g} < threshold {threshold:.3g})")
        if detail:
            msg += f": {detail}"
        msg += (". The robot itself is not singular here; use a parameterization that is "
                f"regular at this pose, e.g. {', '.join(repr(a) for a in self.alternatives)}, "
                "or lower singularity_threshold to accept huge entries.")
        super().__init__(msg)


class KinematicSingularityError(KinematicsError, ValueError):
    """The geometric Jacobian J_e0(q) loses rank: the robot cannot move its frame in some direction."""
