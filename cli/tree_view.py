"""What ``htn plan --tree`` and ``htn run`` show: rich task trees, the
behaviour tree being executed (live, on a terminal) and the one line per
event a pipe gets (display only; the trees live in ``htn.jshop.plans`` and
``htn.executor``)."""

from __future__ import annotations

from collections import deque

import click
from rich.console import Console, Group
from rich.live import Live
from rich.markup import escape
from rich.text import Text
from rich.tree import Tree

from htn.process import silence_stdout

STATUS_STYLE = {"✓": "green", "✕": "bold red", "*": "yellow", "-": "dim"}
LINE_STYLE = {
    "verified": "green",
    "failed": "red",
    "aborted": "bold red",
    "fault": "yellow",
    "retrying": "yellow",
    "replanned": "cyan",
    "replan_failed": "bold red",
    "interrupted": "bold red",
}


def rich_tree(tree):
    """A rich ``Tree`` of the task tree, built breadth-first (no recursion)."""
    root = Tree("[bold]task tree[/bold]")
    queue = deque((root, c) for c in tree.children)
    while queue:
        parent, node = queue.popleft()
        branch = parent.add(_label(node))
        queue.extend((branch, c) for c in node.children)
    return root


def _label(node) -> str:
    text = escape(node.task)
    if node.step is not None:
        return f"[cyan]{text}[/cyan] [dim]step {node.step + 1}[/dim]"
    if node.method:
        return (
            f"[bold]{text}[/bold] [dim]method #{node.method_index + 1}, branch "
            f"{escape(node.branch)} · {escape(node.path)}[/dim]"
        )
    return f"{text} [red](not decomposed)[/red]"


# ---------------------------------------------------------------- the behaviour tree, live


class Row:
    __slots__ = ("depth", "mark", "text", "note", "must")

    def __init__(self, depth, mark, text, note="", must=False):
        self.depth, self.mark, self.text, self.note, self.must = depth, mark, text, note, must


def _actions(b) -> list:
    return [x.htn_action for x in b.iterate() if hasattr(x, "htn_action")]


def _mark(ctxs, running, failed) -> str:
    if failed is not None and any(c is failed for c in ctxs):
        return "✕"
    if all(c.done for c in ctxs):
        return "✓"
    if running is not None and any(c is running for c in ctxs):
        return "*"
    return "-"


class GraftedSteps:
    """Verified steps that a repair grafted out of the behaviour tree (their
    task was re-planned after them), counted by the tasks above them that
    remain, as the run's summary counts them: ``plan 4/4 steps`` beside ``4
    of 4 steps verified``, not the 3 still in the tree. A task is known by
    its node path, which a re-planned task's new subtree keeps (repair
    rebases it on the old one's), the root by the empty path."""

    def __init__(self):
        self.above: dict = {}  # id(action context) -> (context, the paths above it)

    def counts(self, root, done) -> dict:
        """``task path -> verified steps below it that are gone`` (``done``:
        the dispatcher's verified contexts)."""
        present = set()
        for b in root.iterate():
            ctx = getattr(b, "htn_action", None)
            if ctx is None:
                continue
            present.add(id(ctx))
            paths, up = [], b.parent
            while up is not None:
                paths.append(task_path(up))
                up = up.parent
            self.above[id(ctx)] = (ctx, paths)
        gone: dict = {}
        for ctx in done:
            if id(ctx) not in present and id(ctx) in self.above:
                for path in self.above[id(ctx)][1]:
                    gone[path] = gone.get(path, 0) + 1
        return gone


def task_path(b) -> str:
    """The node path of a task's behaviour ('' for the root)."""
    task = getattr(b, "htn_task", None)
    return "" if b.parent is None or task is None else task.path


def behaviour_rows(root, running, failed, events: dict, gone: dict | None = None) -> list[Row]:
    """The rows of the view: every ancestor of the running (or failed) action
    expanded, with its children; other tasks collapsed to one row each.
    ``gone``: verified steps grafted away below a task (:class:`GraftedSteps`),
    counted in its ``done/total steps``."""
    gone = gone or {}
    focus = running if running is not None and not running.done else failed
    path_ids = set()
    if focus is not None:
        node = next((b for b in root.iterate() if getattr(b, "htn_action", None) is focus), None)
        while node is not None:
            path_ids.add(id(node))
            node = node.parent
    rows: list[Row] = []
    stack = [(root, 0)]
    while stack:
        b, depth = stack.pop()
        if hasattr(b, "htn_action"):
            ctx = b.htn_action
            mark = _mark([ctx], focus if focus is running else None, failed)
            on_path = id(b) in path_ids
            note = f"step {ctx.number}" if ctx.done else ""
            if on_path:
                note = f"try {ctx.attempt} · {events.get(id(ctx), '')}"
            rows.append(Row(depth, mark, ctx.text, note, on_path))
            if on_path and ctx.holds and running is ctx and failed is not ctx:
                rows.append(
                    Row(depth + 1, "*", "execute | hold: " + ", ".join(ctx.holds), must=True)
                )
            continue
        ctxs = _actions(b)
        mark = _mark(ctxs, focus if focus is running else None, failed)
        on_path = id(b) in path_ids
        extra = gone.get(task_path(b), 0)
        done = sum(c.done for c in ctxs) + extra
        rows.append(Row(depth, mark, b.name, f"{done}/{len(ctxs) + extra} steps", on_path))
        if on_path or depth == 0:
            stack.extend((c, depth + 1) for c in reversed(b.children))
    return rows


def fit(rows: list[Row], height: int) -> list[tuple[Row, bool]]:
    """At most ``height`` rows: every row marked ``must`` (the running action
    and its ancestors; on a tiny terminal the nearest of them) and as many
    rows around it as fit, nearest first. Each comes with whether rows were
    left out just before it (drawn as ``…`` in its margin, taking no line)."""
    must = [i for i, r in enumerate(rows) if r.must] or [0, len(rows) - 1]
    chosen = set(must[-height:])
    centre = max(must)
    for i in sorted(range(len(rows)), key=lambda i: (abs(i - centre), i < centre)):
        if len(chosen) >= height:
            break
        chosen.add(i)
    out, prev = [], -1
    for i in sorted(chosen):
        out.append((rows[i], i > prev + 1))
        prev = i
    return out


def render_rows(shown: list[tuple[Row, bool]], more_below: bool = False):
    text = Text(no_wrap=True, overflow="ellipsis")
    for k, (r, gap) in enumerate(shown):
        if k:
            text.append("\n")
        text.append("… " if gap else "  ", style="dim")
        text.append("  " * r.depth)
        text.append(r.mark, style=STATUS_STYLE.get(r.mark, ""))
        text.append(" ")
        text.append(r.text, style="bold" if r.must else "")
        if r.note:
            text.append("  " + r.note, style="dim")
    if more_below:
        text.append("\n… ", style="dim")
    return text


class LiveTreeView:
    """The behaviour tree around the running action, redrawn on every event,
    below a scrolling log of what happened (the lines a pipe gets: each
    outcome with its monitor's detail, faults, retries, repairs), which stays
    in the terminal after the run."""

    def __init__(self, dispatcher_ref, console=None):
        self.dispatcher = dispatcher_ref  # a callable returning the dispatcher
        self.console = console or Console()
        self.last: dict = {}  # id(action context) -> last event text
        self.header = ""
        self.grafted = GraftedSteps()
        self.live = Live(
            console=self.console, auto_refresh=False, transient=False, vertical_overflow="crop"
        )

    def __enter__(self):
        self.live.__enter__()
        return self

    def __exit__(self, *exc):
        self._draw()
        return self.live.__exit__(*exc)

    def event(self, rec) -> None:
        d = self.dispatcher()
        if d is None or rec["event"] in ("header", "summary", "tree"):
            return
        from htn.api.run import event_line

        line = event_line(rec)
        if line is not None:  # printed above the live part, which is redrawn below
            self.console.print(Text(line, style=LINE_STYLE.get(rec["event"], "")))
        ctx = d.running
        if ctx is not None and rec["event"] not in ("feedback",):
            self.last[id(ctx)] = f"{rec['event']} {rec['detail']}"[:60]
        self.header = f"sim {rec['sim_t']:.1f} s · {rec['event']}" + (
            f" · step {rec['step']}" if rec["step"] else ""
        )
        self._draw()

    def _draw(self) -> None:
        d = self.dispatcher()
        if d is None:
            return
        height = max(3, self.console.size.height - 3)
        rows = behaviour_rows(
            d.root, d.running, d.failed, self.last, self.grafted.counts(d.root, d.done)
        )
        shown = fit(rows, height)
        below = bool(shown) and shown[-1][0] is not rows[-1]
        self.live.update(
            Group(Text(self.header, style="bold"), render_rows(shown, below)), refresh=True
        )


class PlainView:
    """One line per action outcome, fault and repair (when stdout is not a terminal).

    If the reader goes away (``htn run ... | head``) the lines go to
    /dev/null and the run goes on: a robot does not stop because nobody
    reads its progress. The log and the exit code tell how it ended."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass

    def event(self, rec) -> None:
        from htn.api.run import event_line

        line = event_line(rec)
        if line is None:
            return
        try:
            click.echo(line)
        except BrokenPipeError:
            silence_stdout()
