"""The SHA-256 of a file's bytes, as plan files and logs record it.

``hashlib`` loads OpenSSL's library, which costs 3 ms of CPU, a twentieth of
planning a small problem; CPython's own SHA-256 module gives the same digest
without it (``_sha256`` in 3.11, ``_sha2`` since 3.12). Where neither is
there, ``hashlib`` is used.
"""

from __future__ import annotations

try:
    from _sha256 import sha256 as _sha256  # type: ignore[import-not-found]
except ImportError:  # pragma: no cover - other Pythons
    try:
        from _sha2 import sha256 as _sha256  # type: ignore[import-not-found]
    except ImportError:
        from hashlib import sha256 as _sha256


def sha256_hex(data: bytes) -> str:
    """The SHA-256 of ``data``, as 64 hexadecimal digits."""
    return str(_sha256(data).hexdigest())
