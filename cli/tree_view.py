"""Rich rendering of a task tree (display only; the tree lives in jshop.tree)."""
from __future__ import annotations


def rich_tree(tree):
    """A rich ``Tree`` of the task tree, built breadth-first (no recursion)."""
    from collections import deque
    from rich.tree import Tree
    root = Tree("[bold]task tree[/bold]")
    queue = deque((root, c) for c in tree.children)
    while queue:
        parent, node = queue.popleft()
        branch = parent.add(_label(node))
        queue.extend((branch, c) for c in node.children)
    return root


def _label(node) -> str:
    from rich.markup import escape
    text = escape(node.task)
    if node.step is not None:
        return f"[cyan]{text}[/cyan] [dim]step {node.step + 1}[/dim]"
    if node.method:
        return (f"[bold]{text}[/bold] [dim]method #{node.method_index + 1}, branch "
                f"{escape(node.branch)} · {escape(node.path)}[/dim]")
    return f"{text} [red](not decomposed)[/red]"
