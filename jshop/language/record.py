"""Plain data classes without the cost of ``dataclasses`` at import.

Making a dataclass runs generated code (``__init__``, ``__repr__``, ``__eq__``)
for each class when its module is imported: the syntax objects and the HDDL
model, which every ``htn plan`` imports, took 10 ms of CPU that way, a sixth
of planning a small problem. A :class:`Record` declares its fields as
``__slots__`` and writes its own ``__init__``; it gets a dataclass's
``repr`` and ``==`` (fields in order, the same class only) and, like a
dataclass with ``eq``, no hash. A :class:`FrozenRecord` is hashable and
cannot be changed, as a frozen dataclass.
"""

from __future__ import annotations

from typing import Any


class Record:
    """Fields in ``__slots__`` order: ``repr`` and ``==`` as a dataclass's.
    ``_fields``, where a class sets it, names the slots that are fields (the
    others, such as a plan's ``instance``, are neither shown nor compared)."""

    __slots__: tuple[str, ...] = ()
    _fields: tuple[str, ...] | None = None
    __hash__ = None  # type: ignore[assignment]  # mutable, as a dataclass with eq

    def __repr__(self) -> str:
        names = self._fields or self.__slots__
        fields = ", ".join(f"{k}={getattr(self, k)!r}" for k in names)
        return f"{type(self).__name__}({fields})"

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        names = self._fields or self.__slots__
        return all(getattr(self, k) == getattr(other, k) for k in names)


class FrozenRecord(Record):
    """A record whose fields are set once, in ``__init__`` (with
    ``object.__setattr__``), and that is hashed by them."""

    __slots__: tuple[str, ...] = ()

    def __hash__(self) -> int:  # type: ignore[override]  # hashable again, as a frozen dataclass
        return hash(tuple(getattr(self, k) for k in self.__slots__))

    def __reduce__(self) -> tuple[Any, ...]:
        # pickled (for Dask's workers) and copied as a call with the fields,
        # since setting them one by one is refused
        return (type(self), tuple(getattr(self, k) for k in self.__slots__))

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"cannot assign to field {name!r}: {type(self).__name__} is frozen")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"cannot delete field {name!r}: {type(self).__name__} is frozen")
