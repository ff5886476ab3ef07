"""Private YAML reading for untrusted files: capped in size and in expanded size, safe types only.

A YAML alias (``*name``) repeats the node its anchor (``&name``) marks; nine levels of
ten aliases each make a 700-byte document stand for 10^9 nodes, which ``str()`` of the
result (or an error message quoting it) would expand until memory runs out. So the event
stream is scanned first, counting every node as often as aliases repeat it, and a
document standing for more than :data:`MAX_NODES` nodes is refused before it is built.
Only the safe types are constructed (no Python objects), with LibYAML's C parser where
PyYAML was built with it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ._lazy import lazy_module
from ._text import short

yaml = lazy_module("yaml")  # 10-20 ms: imported with the first YAML file read

MAX_BYTES = 256 * 1024
"""Largest YAML file read [bytes]; the shipped sidecars hold about 2 KiB."""

MAX_NODES = 100_000
"""Most nodes a document may stand for, every alias counted as the nodes it repeats."""


def _loader() -> Any:
    """LibYAML's safe loader where PyYAML was built with it, else PyYAML's."""
    return getattr(yaml, "CSafeLoader", None) or yaml.SafeLoader


class YamlRefused(ValueError):
    """The text is too large, malformed, or stands for too many nodes (message says which)."""


def _expanded_nodes(text: str) -> int:
    """The number of nodes ``text`` stands for, aliases expanded; stops counting past the cap.

    Raises:
        YamlRefused: when the count exceeds :data:`MAX_NODES`.
        yaml.YAMLError: when the text is malformed.
    """
    sizes: dict[str, int] = {}
    open_nodes: list[list[Any]] = [[None, 0]]  # [anchor, nodes so far] of each open collection
    for event in yaml.parse(text, Loader=_loader()):
        if isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            open_nodes.append([event.anchor, 1])
            continue
        if isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            anchor, size = open_nodes.pop()
        elif isinstance(event, yaml.ScalarEvent):
            anchor, size = event.anchor, 1
        elif isinstance(event, yaml.AliasEvent):
            anchor, size = None, sizes.get(event.anchor or "", 1)
        else:
            continue
        if anchor is not None:
            sizes[anchor] = size
        open_nodes[-1][1] += size
        if open_nodes[-1][1] > MAX_NODES:
            raise YamlRefused(
                f"the document stands for more than {MAX_NODES} nodes once its aliases (*name) are "
                "expanded; aliases that repeat large parts are refused"
            )
    return int(open_nodes[0][1])


def read_head(path: Path) -> bytes:
    """The first :data:`MAX_BYTES` + 1 bytes of a file: enough for :func:`load_yaml` to refuse a larger one.

    Raises:
        OSError: when the file cannot be read.
    """
    with path.open("rb") as f:
        return f.read(MAX_BYTES + 1)


def load_yaml(text: str | bytes) -> Any:
    """Parse untrusted YAML text into plain data (mappings, lists, strings, numbers, booleans, None).

    Args:
        text: the document.

    Returns:
        The loaded document.

    Raises:
        YamlRefused: the text is larger than :data:`MAX_BYTES`, is not valid YAML (line and
            column given), or stands for more than :data:`MAX_NODES` nodes with aliases expanded.
    """
    size = len(text.encode() if isinstance(text, str) else text)
    if size > MAX_BYTES:
        raise YamlRefused(f"the file is larger than {MAX_BYTES // 1024} KiB, the most read from a YAML file")
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise YamlRefused(f"not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    try:
        _expanded_nodes(text)
        return yaml.load(text, Loader=_loader())
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise YamlRefused(f"malformed YAML{where}: {short(problem, quote=False)}") from None
