"""The world state: ground atoms and protection counters (manual 5.1.2, 3.9).

Atoms are kept per predicate in insertion order, exactly like JSHOP2's
``State``: new atoms are appended, a deleted atom is remembered with its index
and put back at that index on backtracking. Satisfiers are enumerated in this
order, so keeping it is what makes plans come out in JSHOP2's order.
"""

from __future__ import annotations

from collections.abc import Iterator

from htn.jshop.language.terms import is_ground


class State:
    __slots__ = ("atoms", "members", "protections", "nonground")

    def __init__(self):
        self.atoms: dict[str, list] = {}  # pred -> [args tuple], in order
        self.members: dict[str, set] = {}  # pred -> {ground args tuple}
        self.protections: dict[tuple, int] = {}  # (pred, args) -> counter
        self.nonground = 0  # atoms with variables in them (see htn.jshop.logic.modes)

    def bucket(self, pred: str) -> list:
        """The live list of ``pred``'s atoms (created empty on first use)."""
        lst = self.atoms.get(pred)
        if lst is None:
            lst = self.atoms[pred] = []
            self.members[pred] = set()
        return lst

    def has(self, pred: str, args: tuple) -> bool:
        m = self.members.get(pred)
        return m is not None and args in m

    def add(self, pred: str, args: tuple) -> bool:
        """Append an atom; False if it was already there (nothing changes)."""
        m = self.members.get(pred)
        if m is None:
            self.bucket(pred)
            m = self.members[pred]
        for x in args:  # is_ground(args), the common flat atom without a call
            tx = type(x)
            if tx is not str and tx is not float and not is_ground(x):
                self.nonground += 1
                break
        else:
            if args in m:
                return False
            m.add(args)
        self.atoms[pred].append(args)
        return True

    def delete(self, pred: str, args: tuple) -> int:
        """Remove an atom; return its former index, or -1 if absent.

        A non-ground atom never equals a state atom in JSHOP2, so it is never
        deleted.
        """
        m = self.members.get(pred)
        if m is None or args not in m:
            return -1
        lst = self.atoms[pred]
        i = lst.index(args)
        del lst[i]
        m.discard(args)
        return i

    def restore(self, pred: str, args: tuple, index: int) -> None:
        self.atoms[pred].insert(index, args)
        if is_ground(args):
            self.members[pred].add(args)
        else:
            self.nonground += 1

    def retract(self, pred: str, args: tuple) -> None:
        """Undo an :meth:`add` (the atom was appended, so look from the end)."""
        lst = self.atoms[pred]
        if lst[-1] == args:  # undone in reverse order: usually still the last
            lst.pop()
        else:
            for i in range(len(lst) - 2, -1, -1):
                if lst[i] == args:
                    del lst[i]
                    break
        m = self.members[pred]
        if args in m:
            m.remove(args)
        else:  # only ground atoms are members
            self.nonground -= 1

    def is_protected(self, pred: str, args: tuple) -> bool:
        return (pred, args) in self.protections

    def protect(self, pred: str, args: tuple) -> None:
        key = (pred, args)
        self.protections[key] = self.protections.get(key, 0) + 1

    def unprotect(self, pred: str, args: tuple) -> bool:
        key = (pred, args)
        n = self.protections.get(key)
        if n is None:
            return False
        if n <= 1:
            del self.protections[key]
        else:
            self.protections[key] = n - 1
        return True

    def copy(self) -> State:
        s = State()
        s.atoms = {p: list(v) for p, v in self.atoms.items()}
        s.members = {p: set(v) for p, v in self.members.items()}
        s.protections = dict(self.protections)
        s.nonground = self.nonground
        return s

    def facts(self) -> Iterator[tuple[str, tuple]]:
        """All atoms as ``(pred, args)``, predicates in first-use order."""
        for pred, lst in self.atoms.items():
            for args in lst:
                yield pred, args

    def __len__(self) -> int:
        return sum(len(v) for v in self.atoms.values())


class HashedState(State):
    """A state that keeps a hash of its atoms up to date (``key``), so that
    two states can be compared in constant time (see :mod:`htn.jshop.search.loops`).
    Equal states have equal keys; unequal states almost surely differ."""

    __slots__ = ("key",)

    def __init__(self):
        super().__init__()
        self.key = 0

    def add(self, pred: str, args: tuple) -> bool:
        if State.add(self, pred, args):
            self.key ^= hash((pred, args))
            return True
        return False

    def delete(self, pred: str, args: tuple) -> int:
        i = State.delete(self, pred, args)
        if i != -1:
            self.key ^= hash((pred, args))
        return i

    def restore(self, pred: str, args: tuple, index: int) -> None:
        State.restore(self, pred, args, index)
        self.key ^= hash((pred, args))

    def retract(self, pred: str, args: tuple) -> None:
        State.retract(self, pred, args)
        self.key ^= hash((pred, args))


class Change:
    """What one operator application did, to be undone on backtracking."""

    __slots__ = ("deleted", "added", "unprotected", "protected")

    def __init__(self):
        self.deleted: list = []  # (pred, args, index)
        self.added: list = []  # (pred, args)
        self.unprotected: list = _NONE  # (pred, args); a list of its own once used
        self.protected: list = _NONE  # (pred, args)

    def undo(self, state: State) -> None:
        """JSHOP2's ``State.undo``: added out, deleted back in place, protections."""
        for pred, args in self.added:
            state.retract(pred, args)
        for pred, args, index in reversed(self.deleted):
            state.restore(pred, args, index)
        for pred, args in self.protected:
            state.unprotect(pred, args)
        for pred, args in self.unprotected:
            state.protect(pred, args)


_NONE: tuple = ()  # no protection changes (most operators): nothing allocated
