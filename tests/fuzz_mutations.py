"""Mutations of an input file for the fuzz tests (:mod:`test_fuzz`,
:mod:`test_fuzz_inputs`): whole expressions and words moved, deleted,
duplicated or replaced (the result still parses, and reaches the checks
and the planner), and raw slips of characters (it does not), some of them
breaking UTF-8."""

from __future__ import annotations

import re

from hypothesis import strategies as st

# what a mutation may insert: the language's pieces, and the inputs the
# audit found crashes with
TOKENS = [
    "(",
    ")",
    "((",
    "))",
    "()",
    "nil",
    "NIL",
    "?x",
    "?y",
    "?new",
    "a",
    "b",
    "0",
    "-1",
    "3.5",
    "1e400",
    "-0",
    "!op",
    "!!op",
    ":unordered",
    ":immediate",
    ":first",
    "and",
    "or",
    "not",
    "imply",
    "forall",
    "assign",
    "call",
    ":method",
    ":operator",
    ":-",
    ":protection",
    ":sort-by",
    "(call - )",
    "(call -)",
    "(call + ?x a)",
    "(call / 1 0)",
    "(call member a b)",
    "(call undefinedfn 1)",
    "(a . b)",
    "(?x . ?y)",
    ". ",
    "(not (p ?z))",
    "(forall (?x) (p ?x) (q ?x))",
    "(assign ?z (call + 1 2))",
    "(:sort-by ?x < (p ?x))",
    "(:sort-by ?x > (p ?x))",
    "(:first (p ?x))",
    "(:operator (!o ?a) () () ((r ?b)))",
    "(:method (m ?a) () ((!o ?a ?a)))",
    "(defproblem p other () ())",
    "defdomain",
    "defproblem",
    ";",
    "; comment\n",
    "\n",
    "\t",
    "é",
    "\ufeff",
    "\x00",
    "#",
    '"',
    "'",
    "{",
    "\\",
    " ".join(f"(p{i} ?x)" for i in range(25)),
    "(" * 40 + "a" + ")" * 40,
    # HDDL
    ":parameters",
    ":task",
    ":subtasks",
    ":ordered-subtasks",
    ":ordering",
    "(< t1 t2)",
    "(t2 < t1)",
    "- object",
    "- undeclared_type",
    "(exists (?v - object) (p ?v))",
    "(when (p ?x) (not (p ?x)))",
    "(= ?x ?y)",
    "(imply (p a) (q a))",
    ":precondition ()",
    "(:goal (and))",
    "(define (domain other))",
]


@st.composite
def mutants(draw, text: str) -> bytes:
    """``text`` with one to four mutations, as bytes (some break UTF-8).
    Most mutations move whole expressions or words, so that many mutants
    get past the parser into the checks and the planner."""
    for _ in range(draw(st.integers(1, 4))):
        raw = draw(st.integers(0, 4)) == 0
        text = draw(_mutation(text) if raw else _balanced_mutation(text))
    data = text.encode("utf-8", "surrogatepass")
    if draw(st.integers(0, 39)) == 0:  # bytes that are not UTF-8
        at = draw(st.integers(0, len(data)))
        data = (
            data[:at] + draw(st.sampled_from([b"\xff", b"\xc3", b"\xe2\x82", b"\x80"])) + data[at:]
        )
    if draw(st.integers(0, 39)) == 0:
        data = b"\xef\xbb\xbf" + data
    return data


def _mutation(text: str):
    n = len(text)
    position = st.integers(0, n)
    span = st.tuples(position, st.integers(1, 80)).map(lambda t: (t[0], min(n, t[0] + t[1])))
    words = list(re.finditer(r"[^\s()]+", text))

    def delete(s):
        return text[: s[0]] + text[s[1] :]

    def duplicate(s):
        return text[: s[1]] + text[s[0] : s[1]] + text[s[1] :]

    def insert(args):
        at, token = args
        return text[:at] + " " + token + " " + text[at:]

    def nest(args):
        (a, b), depth = args
        return text[:a] + "(" * depth + text[a:b] + ")" * depth + text[b:]

    def truncate(at):
        return text[:at]

    options = [
        span.map(delete),
        span.map(duplicate),
        st.tuples(position, st.sampled_from(TOKENS)).map(insert),
        st.tuples(span, st.sampled_from([1, 3, 200, 1001, 10_000])).map(nest),
        position.map(truncate),
    ]
    if len(words) > 1:
        pick = st.integers(0, len(words) - 1)

        def replace(args):
            i, token = args
            w = words[i]
            return text[: w.start()] + token + text[w.end() :]

        def swap(args):
            i, j = sorted(args)
            if i == j:
                return text
            a, b = words[i], words[j]
            return (
                text[: a.start()]
                + b.group()
                + text[a.end() : b.start()]
                + a.group()
                + text[b.end() :]
            )

        options += [
            st.tuples(pick, st.sampled_from(TOKENS + [w.group() for w in words[:50]])).map(replace),
            st.tuples(pick, pick).map(swap),
        ]
    return st.one_of(options)


def _expressions(text: str) -> list[tuple[int, int]]:
    """Spans of the parenthesised expressions of ``text`` (comments ignored)."""
    spans, open_ = [], []
    for m in re.finditer(r"[()]|;[^\n]*", text):
        if m.group() == "(":
            open_.append(m.start())
        elif m.group() == ")" and open_:
            spans.append((open_.pop(), m.end()))
    return spans


def _balanced_mutation(text: str):
    """Delete, duplicate, move or replace a whole expression, or replace a
    word with another word of the same file: the result still parses."""
    spans = _expressions(text)
    words = [m.group() for m in re.finditer(r"[^\s()]+", text)] or ["a"]
    if len(spans) < 2:
        return st.just(text)
    span = st.sampled_from(spans)

    def delete(s):
        return text[: s[0]] + text[s[1] :]

    def duplicate(s):
        return text[: s[1]] + " " + text[s[0] : s[1]] + text[s[1] :]

    def replace(args):
        (a, b), (c, d) = args
        return text[:a] + text[c:d] + text[b:]

    def reword(args):
        (a, b), old, new = args
        return (
            text[:a]
            + re.sub(rf"(?<![^\s(]){re.escape(old)}(?![^\s)])", lambda m: new, text[a:b], count=1)
            + text[b:]
        )

    return st.one_of(
        span.map(delete),
        span.map(duplicate),
        st.tuples(span, span).map(replace),
        st.tuples(span, st.sampled_from(words), st.sampled_from(words + TOKENS)).map(reword),
    )


def text_mutant(text: str, rng, inserts: list[str]) -> str:
    """One random slip of ``text`` (``rng``: a :class:`random.Random`), for
    the fast readers' tests: a character less, one of ``inserts`` more, a
    word in the other case, a list or a stretch taken out, a stretch copied
    elsewhere."""
    k = rng.randrange(len(text))
    kind = rng.randrange(5)
    if kind == 0:  # a character less
        return text[:k] + text[k + 1 :]
    if kind == 1:  # something more
        return text[:k] + rng.choice(inserts) + text[k:]
    if kind == 2:  # a word in other case
        j = k
        while j < len(text) and text[j].isalnum():
            j += 1
        return text[:k] + text[k:j].swapcase() + text[j:]
    if kind == 3:  # a list taken out whole, or a stretch of text
        j = text.find(")", k)
        return text[:k] + text[j + 1 :] if j >= 0 else text[:k]
    i = rng.randrange(len(text))  # a stretch copied elsewhere
    a, b = sorted((k, i))
    return text[:b] + text[a : a + rng.randrange(1, 12)] + text[b:]
