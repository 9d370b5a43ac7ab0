"""Type stub of the C batch chain kinengine/kinematics/chainkernel.c (see kinengine/kinematics/chain.py)."""

from typing import Any

class Kernel:
    def __init__(self, dof: int, program: bytes) -> None: ...
    def run(self, Q: Any, T: Any, J: Any, reference: int, /) -> None: ...
    def candidates(
        self,
        Q: Any,
        row: Any,
        T: Any,
        base: Any,
        table: Any,
        out: Any,
        shifts: Any,
        has_ref: bool,
        within: bool,
        skip: bool,
        accept: float,
        same: float,
        turn_tol: float,
        /,
    ) -> None: ...

def sin_check(angles: bytes, /) -> bytes: ...
