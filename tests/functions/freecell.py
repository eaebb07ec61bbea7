"""User function of JSHOP2's freecell example (its Java class CheckNull)."""


def CheckNull(first, second):
    """Return ``second`` when ``first`` is nil, otherwise the number 0."""
    return second if first == [] else 0
