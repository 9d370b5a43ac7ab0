"""The optional C accelerator of the hot path (kinengine/model/accelerator.py says what it does); everything
else about the build is in pyproject.toml. Both extensions are optional: without a C compiler the build goes
on and kinengine runs the same code in pure Python. fastcall.c reads arrays through numpy's C API, so it is
compiled against numpy's headers (numpy >= 2 in build-system.requires: its extensions also run on numpy 1.26).
"""

import numpy
from setuptools import Extension, setup

setup(
    ext_modules=[
        Extension(
            "kinengine.model.fastcall",
            ["kinengine/model/fastcall.c"],
            include_dirs=[numpy.get_include()],
            optional=True,
        ),
        Extension("kinengine.kinematics.chainkernel", ["kinengine/kinematics/chainkernel.c"], optional=True),
    ]
)
