"""Reading a TOML input file (scene, sweep, design) safely: a regular file, of bounded size, UTF-8, TOML."""

from __future__ import annotations

import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["MAX_TOML_BYTES", "read_toml_file"]

MAX_TOML_BYTES = 4 * 2**20    # a scene, sweep or design file is a few kB; more is not one (or is /dev/zero)


def read_toml_file(path: str | Path, what: str) -> dict:
    """The parsed TOML document of ``path``; a missing file, a folder, anything but a regular file (a named pipe, a
    device such as /dev/zero: refused before opening, so nothing hangs), a file over MAX_TOML_BYTES, a file that is
    not UTF-8 text or not TOML raises an error (FileNotFoundError, IsADirectoryError, ValueError) naming ``what``
    and the file."""
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"{what} {str(path)!r} is a folder, not a TOML file")
    if not path.exists():
        raise FileNotFoundError(f"{what} {str(path)!r} does not exist")
    if not path.is_file():
        raise ValueError(f"{what} {str(path)!r} is not a regular file (a named pipe, a socket or a device): give a "
                         f"TOML file")
    try:
        with path.open("rb") as stream:
            raw = stream.read(MAX_TOML_BYTES + 1)
    except OSError as error:
        raise OSError(f"{what} {str(path)!r} cannot be read: {error.strerror or error}") from None
    if len(raw) > MAX_TOML_BYTES:
        raise ValueError(f"{what} {str(path)!r} is larger than {MAX_TOML_BYTES // 2**20} MiB: not a TOML input file")
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise ValueError(f"{what} {str(path)!r} is UTF-16 text: save it as UTF-8 (TOML files are UTF-8)")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"{what} {str(path)!r} is not UTF-8 text (byte {error.start} is "
                         f"{raw[error.start:error.start + 1]!r}): a TOML file is UTF-8 text") from None
    if "\x00" in text:
        raise ValueError(f"{what} {str(path)!r} holds NUL bytes: a binary file, not TOML")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"{what} {str(path)!r}: not valid TOML ({error})") from None
