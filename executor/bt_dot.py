"""The behaviour tree as Graphviz DOT, each node named for what it is.

py_trees' DOT export (:func:`py_trees.display.dot_tree`) names a node by its
behaviour's name, and makes repeated names unique by appending ``*``: every
action subtree has an ``attempt``, an ``execute`` and a ``monitor``, so a plan
of twelve steps shows ``attempt***********``. It also prefixes a sequence with
memory with ``Ⓜ`` and a synchronised parallel with ``⚡``, glyphs Graphviz's
default fonts lack (they render as an empty box).

Here each behaviour of an action's subtree is named by its role and its step
(``attempt (!grasp jenny pringles kitchen_counter)``), a task's sequence by
its node path, and the export is py_trees' own (shapes, colours, policies);
only the labels are rewritten: the role and the step on two lines, the
glyphs as words (``with memory``, ``synchronised``). A ``:`` in a node path
(``:call 2``) would be read by pydot as a port: node names carry U+2236 (it
looks alike), labels the ``:`` itself.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from py_trees.behaviour import Behaviour

    from .behaviours import ActionContext

GLYPHS = {"Ⓜ": "with memory", "⚡": "synchronised"}  # py_trees' unicode prefixes


def behaviour_tree_dot(root: Behaviour) -> str:
    """The DOT text of the behaviour tree under ``root``."""
    import py_trees

    names = {b: b.name for b in root.iterate()}
    labels: dict[str, str] = {}
    taken: dict[str, int] = {}
    for b in names:
        label = _label(b)
        name = label.replace("\n", " ").replace(":", "\u2236")
        taken[name] = taken.get(name, 0) + 1
        if taken[name] > 1:  # the same step twice in the plan
            name = f"{name} [{taken[name]}]"
        labels[name] = label
        b.name = name
    try:
        graph = py_trees.display.dot_tree(root)
    finally:
        for b, name in names.items():
            b.name = name
    for node in graph.get_nodes():
        name = node.get_name().strip('"')
        if name in labels:
            # pydot's set_label / get_label, which it makes at run time
            node.set("label", _with_words(node.get("label") or "", name, labels[name]))
    return graph.to_string()


def _label(b: Behaviour) -> str:
    """What a behaviour is: its role and step, or its task's node path."""
    ctx = _action_of(b)
    if ctx is None or getattr(b, "htn_action", None) is ctx:
        return b.name  # a task's sequence, or the step itself
    return f"{b.name}\n{ctx.text}"


def _action_of(b: Behaviour) -> ActionContext | None:
    """The action context of the action subtree ``b`` belongs to, if any."""
    node: Behaviour | None = b
    while node is not None:
        ctx: ActionContext | None = getattr(node, "htn_action", None)
        if ctx is not None:
            return ctx
        node = node.parent
    return None


def _with_words(shown: str, name: str, label: str) -> str:
    """py_trees' label for node ``name`` (glyph prefix, name, policy line)
    with the readable ``label`` for the name and words for the glyphs."""
    shown = shown.strip('"').replace("\\n", "\n")
    words = []
    for glyph, word in GLYPHS.items():
        if shown.startswith(glyph) or shown.startswith(f"{glyph} "):
            words.append(word)
        shown = shown.replace(glyph, "")
    shown = shown.strip().replace(name, label, 1)
    policy = shown[len(label) :].strip() if shown.startswith(label) else ""
    extra = ", ".join(x for x in (policy, *words) if x)
    return f"{label}\n{extra}" if extra else label
