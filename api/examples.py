"""The examples use case: the bundled domains and problems, listed with what
each is, or copied to a folder to start from (``htn examples [DIR]``).

* :func:`list_examples` - (folder, file name, description) of each bundled
  domain and problem;
* :func:`copy_examples` - copy them all into ``DIR/domains`` and
  ``DIR/problems``.

They are found in :data:`EXAMPLES` (:data:`htn.installation.EXAMPLES`); an
installation without them is an :class:`~htn.jshop.language.errors.HtnError`
at that folder.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from htn.installation import EXAMPLES
from htn.jshop.language.errors import HtnError

if TYPE_CHECKING:
    from .inputs import StrPath

__all__ = ["EXAMPLES", "FOLDERS", "bundled", "summary", "list_examples", "copy_examples"]

# the folders copied and the files of each (retry limits beside the domains)
FOLDERS = {"domains": ("*.jshop", "*.toml"), "problems": ("*.jshop",)}


def bundled() -> list[Path]:
    """The bundled example files, domains first (retry limits beside them);
    none found is an input error."""
    out: list[Path] = []
    for folder, patterns in FOLDERS.items():
        for pattern in patterns:
            out.extend(sorted((EXAMPLES / folder).glob(pattern)))
    if not out:
        raise HtnError("no bundled examples found in this installation", str(EXAMPLES))
    return out


def summary(path: Path) -> str:
    """The first sentence of a file's leading comment (its description)."""
    words: list[str] = []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        text = line.strip()
        if not text.startswith(";") and not text.startswith("#"):
            break
        words.append(text.lstrip(";# ").strip())
    text = " ".join(w for w in words if w)
    end = re.search(r"\.\s+(?=[A-Z\"(])", text)  # not "Fig. 7"
    return text[: end.start() + 1] if end else text


def list_examples() -> list[tuple[str, str, str]]:
    """(folder, file name, first sentence of its comment) of each bundled
    domain and problem (``.jshop`` files), domains first."""
    return [(f.parent.name, f.name, summary(f)) for f in bundled() if f.suffix == ".jshop"]


def copy_examples(dest: StrPath, force: bool = False) -> list[Path]:
    """Copy the bundled examples into ``dest/domains`` and ``dest/problems``
    (made as needed); the files written.

    A file there already is an input error unless ``force``; even with it,
    one that is no regular file (a device, a FIFO) or is a bundled file
    itself (through a link) is refused before anything is copied
    (:func:`htn.files.check_target`)."""
    target = Path(dest)
    pairs = [(f, target / f.parent.name / f.name) for f in bundled()]
    clash = [str(t) for _, t in pairs if t.exists()]
    if clash and not force:
        raise HtnError(
            f"{len(clash)} file(s) exist already, e.g. {clash[0]} (use --force to overwrite)",
            str(dest),
        )
    from htn.files import check_target

    for src, dst in pairs:  # no device, FIFO or bundled file itself is written over
        if dst.exists() or dst.is_symlink():
            check_target(str(dst), None, [src])
    for src, dst in pairs:
        try:
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, dst)
        except OSError as exc:
            raise HtnError(f"cannot copy {src.name}: {exc.strerror}", str(dst)) from exc
    return [dst for _, dst in pairs]
