"""Type stub of the C batch chain kinengine/kinematics/chainkernel.c (see kinengine/kinematics/chain.py)."""

from typing import Any

class Kernel:
    def __init__(self, dof: int, program: bytes) -> None: ...
    def run(self, Q: Any, T: Any, J: Any, reference: int, /) -> None: ...
