"""Type stub of the C accelerator kinengine/model/fastcall.c (see kinengine/model/accelerator.py)."""

from collections.abc import Callable
from typing import Any

class Ready:
    def __init__(self, dof: int, limit: float) -> None: ...
    def check(self, q: object, /) -> bool: ...

class FrameCalls:
    def __init__(self, **bound: Any) -> None: ...
    pose: Callable[..., Any]
    jacobian: Callable[..., Any]
    kinematics: Callable[..., Any]
