"""``kinengine bench``: latency and throughput of kinengine next to raw Pinocchio and peer libraries
(:mod:`.cases` what is timed and its floor, :mod:`.run` the interleaved timing, :mod:`.peers` the
peer libraries, :mod:`.command` the command line)."""

from .command import add_parser

__all__ = ["add_parser"]
