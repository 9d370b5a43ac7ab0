"""Where the viewer listens: the ``host`` and ``port`` options checked before viser is started.

viser retries the next port without end when it cannot listen, so an unresolvable name or an address
of another machine hung :func:`kinengine.presentation.viewer.view` forever, and ``host=''`` (or None)
listened on every interface while the printed URL said 127.0.0.1. Owns :func:`listen_address`: the
host resolved within :data:`RESOLVE_SECONDS`, tried once with a bind on this machine, and a one-line
``UserWarning`` when it is not a loopback address (anyone who reaches it drives the robot's display).
"""

from __future__ import annotations

import ipaddress
import socket
import threading
import warnings

from ..errors import OptionError

RESOLVE_SECONDS = 5.0
"""Longest wait for the host name to resolve [s]."""


def checked_port(port: object) -> int | None:
    """``port`` as an int 0..65535 or None; OptionError otherwise (a bool is not a port)."""
    if port is None:
        return None
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise OptionError(f"port must be an integer 0..65535 (0: any free port), got {port!r}")
    return int(port)


def listen_address(host: object) -> str:
    """The numeric address ``host`` resolves to, checked to be one this machine can listen on.

    OptionError for None, a non-string or an empty host (say "0.0.0.0" to serve every interface), a
    name that does not resolve within RESOLVE_SECONDS, or an address of another machine. Warns (one
    line) when the address is not a loopback one.
    """
    if not isinstance(host, str) or not host.strip():
        raise OptionError(
            f"host must be an address to listen on, e.g. '127.0.0.1' (this machine only) or '0.0.0.0' "
            f"(every interface), got {host!r}"
        )
    found: list[object] = []

    def resolve() -> None:
        try:
            found.append(socket.getaddrinfo(host, None, type=socket.SOCK_STREAM))
        except (OSError, UnicodeError) as exc:
            found.append(exc)

    worker = threading.Thread(target=resolve, name="kinengine viewer host lookup", daemon=True)
    worker.start()
    worker.join(RESOLVE_SECONDS)
    if not found:
        raise OptionError(f"host {host!r} did not resolve within {RESOLVE_SECONDS:g} s; give an IP address")
    result = found[0]
    if isinstance(result, BaseException) or not result:
        reason = getattr(result, "strerror", None) or result
        raise OptionError(f"host {host!r} does not resolve ({reason}); give an address of this machine")
    family, _, _, _, sockaddr = result[0]  # type: ignore[index]
    address = str(sockaddr[0])
    try:
        with socket.socket(family, socket.SOCK_STREAM) as probe:
            probe.bind((address, 0))
    except OSError as exc:
        raise OptionError(
            f"cannot listen on host {host!r} ({address}): {exc.strerror or exc}; give an address of this "
            "machine, e.g. '127.0.0.1' or '0.0.0.0'"
        ) from None
    ip = ipaddress.ip_address(address.split("%")[0])
    if not ip.is_loopback:
        where = "every interface" if ip.is_unspecified else address
        warnings.warn(
            f"the viewer listens on {where} (host {host!r}): anyone who can reach this machine's port can "
            "open the page and drive the robot's display",
            UserWarning,
            stacklevel=3,
        )
    return address


def url(address: str, port: int) -> str:
    """A URL that reaches a server listening on ``address``:``port`` from this machine."""
    ip = ipaddress.ip_address(address.split("%")[0])
    if ip.is_unspecified:
        address = "127.0.0.1" if ip.version == 4 else "::1"
    return f"http://[{address}]:{port}" if ":" in address else f"http://{address}:{port}"


__all__ = ["RESOLVE_SECONDS", "checked_port", "listen_address", "url"]
