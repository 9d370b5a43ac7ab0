"""The kinengine exception hierarchy.

Every error kinengine raises derives from :class:`KinematicsError`; each
subclass also derives from the builtin a caller would naturally catch
(``ValueError`` for bad values, ``KeyError`` for unknown names).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence


class KinematicsError(Exception):
    """Base class of every kinengine error.

    Every kinengine error pickles (so it crosses process boundaries, e.g. out of a
    ``multiprocessing.Pool`` worker) and deep-copies: it is rebuilt with the arguments its
    constructor was given, then its attributes are restored. Its message is one line: line breaks in a
    message (e.g. the repr of an array that was passed where a name belongs) become spaces; only
    :class:`KinematicSingularityError`, whose message is the singularity report, keeps its lines.
    """

    multiline = False

    def __init__(self, *args: object) -> None:
        if not self.multiline and len(args) == 1 and isinstance(args[0], str) and "\n" in args[0]:
            args = (re.sub(r"\s*[\r\n]+\s*", " ", args[0]),)
        super().__init__(*args)

    def __reduce__(self) -> tuple:
        args, kwargs = self.__dict__.get("_init", (self.args, {}))
        return _rebuild, (type(self), tuple(args), dict(kwargs)), dict(self.__dict__)


def _rebuild(cls: type, args: tuple, kwargs: dict) -> KinematicsError:
    """An error of class ``cls`` made again from its constructor arguments (the pickle path)."""
    return cls(*args, **kwargs)


class URDFError(KinematicsError, ValueError):
    """A robot description is missing, unreadable, malformed or unsupported.

    ``source`` names the file (or ``"<string>"``), ``element`` the offending
    element (e.g. ``"joint 'elbow'"``) and ``line`` its line number when known.
    """

    def __init__(
        self, message: str, *, source: str | None = None, element: str | None = None, line: int | None = None
    ) -> None:
        self._init = ((message,), {"source": source, "element": element, "line": line})
        self.source = source
        self.element = element
        self.line = line
        where = []
        if source:
            where.append(f"{source}" + (f":{line}" if line else ""))
        if element:
            where.append(element)
        prefix = ", ".join(where)
        message = re.sub(r"\s*[\r\n]+\s*", " ", str(message))  # one line, e.g. a libxml2 message or an array
        super().__init__(f"{prefix}: {message}" if prefix else message)


class MJCFError(URDFError):
    """An MJCF (MuJoCo XML) model is unreadable, refused by MuJoCo's compiler, or holds what a fixed-base
    kinematic tree cannot (a ball joint, a nonlinear joint coupling). A :class:`URDFError`, so code that
    catches a bad description catches it; ``source`` names the MJCF file, ``element`` the body or joint."""


class FrameNotFoundError(KinematicsError, KeyError):
    """A frame (or joint) name is not part of the model.

    The message suggests the closest known names.
    """

    def __init__(self, name: object, known: Iterable[str], *, kind: str = "frame") -> None:
        self.name = name
        self.known = list(known)
        self._init = ((name, self.known), {"kind": kind})
        import difflib  # only when a name is unknown (difflib costs ~1 ms at import)

        close = difflib.get_close_matches(str(name), self.known, n=3, cutoff=0.5)
        hint = (
            f" Did you mean {', '.join(repr(c) for c in close)}?"
            if close
            else f" Known {kind}s: {', '.join(self.known[:12])}"
            + (", ..." if len(self.known) > 12 else "")
            + "."
        )
        shown = " ".join(repr(name).split())  # one line, e.g. for a numpy array
        shown = shown if len(shown) <= 80 else shown[:77] + "..."
        self.message = f"unknown {kind} {shown}.{hint}"
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
    def unknown(cls, kind: str, name: object, valid: Sequence[str]) -> ParameterizationError:
        return cls(f"unknown {kind} parameterization {name!r}; valid names: {', '.join(valid)}")


class RepresentationSingularityError(KinematicsError, ValueError):
    """The pose parameterization is singular (E_e(χ) has no finite value) here.

    This is a property of the chosen coordinates χ: another parameterization (``alternatives``) is
    regular at the same pose. Whether the robot is *also* kinematically singular there is decided
    from the geometric Jacobian's singular values by the code that raises: ``robot_rank`` is the rank of
    J_e0 (σ_i > 1e-6·σ_max) and ``full_rank`` its generic rank min(6, dof); both None when no robot is
    involved (a parameterization evaluated on its own). The message says which is the case.
    """

    def __init__(
        self,
        parameterization: str,
        distance: float,
        threshold: float,
        alternatives: Sequence[str],
        detail: str = "",
        robot_rank: int | None = None,
        full_rank: int | None = None,
    ) -> None:
        self.parameterization = parameterization
        self.distance = distance
        self.threshold = threshold
        self.alternatives = list(alternatives)
        self.detail = detail
        self.robot_rank = robot_rank
        self.full_rank = full_rank
        args = (parameterization, distance, threshold, self.alternatives, detail, robot_rank, full_rank)
        self._init: tuple[tuple[object, ...], dict[str, object]] = (args, {})
        msg = (
            f"{parameterization!r} is at a representation singularity "
            f"(distance {distance:.3g} < threshold {threshold:.3g})"
        )
        if detail:
            msg += f": {detail}"
        if robot_rank is None or full_rank is None:
            robot = ". This is a property of the parameterization, not of a robot"
        elif robot_rank < full_rank:
            robot = (
                f". The robot itself is also kinematically singular here "
                f"(rank {robot_rank} of {full_rank}), "
                "which no parameterization removes. For the representation singularity"
            )
        else:
            robot = f". The robot itself is not singular here (rank {robot_rank} of {full_rank})"
        msg += (
            f"{robot}: use a parameterization that is regular at this pose, e.g. "
            f"{', '.join(repr(a) for a in self.alternatives)}, or lower singularity_threshold to accept "
            "huge entries, or pass on_singularity='nan'."
        )
        super().__init__(msg)


class KinematicSingularityError(KinematicsError, ValueError):
    """The geometric Jacobian J_e0(q) loses rank: the robot cannot move its frame in some direction."""

    multiline = True  # the message is the SingularityReport, one line per lost direction
    report: object | None = None
    """The kinengine.control.manipulability.SingularityReport behind the message when raised by
    require_regular (typed ``object``: this bottom layer cannot import the control layer's class)."""


class ResourceLimitError(KinematicsError, MemoryError):
    """kinengine would need more memory than the process may use (e.g. one more thread's Pinocchio Data
    of a large model under a memory cap); the message gives the size, the memory left and the fix."""


def pinocchio_import_hint(exc: ImportError) -> str | None:
    """What to do when ``import pinocchio`` fails for a missing C++ library, or None for any other failure.
    pin 3.x wheels link liburdfdom*.so.4.0 and libtinyxml2.so.10 but let pip install newer ones
    (docs/installing.md, Pinocchio 3.x)."""
    text = str(exc)
    if "liburdfdom" not in text and "libtinyxml2" not in text:
        return None
    return (
        f"Pinocchio does not load ({text}): a pin 3.x wheel beside too new C++ libraries; "
        "pip install 'cmeel-urdfdom<5' 'cmeel-tinyxml2<11' (or pin 4.x)"
    )
