"""User function and comparator of JSHOP2's ``test`` example (MyFunc, MyComparator)."""


def MyFunc(*numbers):
    """The sum of the numeric arguments."""
    return sum(n for n in numbers if isinstance(n, float))


def MyComparator(a, b):
    """-1 when ``a`` (truncated to an integer) is odd; else 1 when ``b`` is odd; else 0.

    Deliberately inconsistent, like the Java original: the resulting order
    depends on the exact sort algorithm (Java's TimSort).
    """
    if int(a) % 2 != 0:
        return -1
    if int(b) % 2 != 0:
        return 1
    return 0
