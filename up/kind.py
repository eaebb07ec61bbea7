"""The problem features the ``htn`` engine supports, as a UP ``ProblemKind``.

Exactly what the in-memory conversion (:mod:`htn.up.convert`) turns into the
planner's model and what the planner then solves with HDDL's semantics
(Höller et al., AAAI 2020): hierarchical problems with typed objects,
boolean fluents (predicates, closed world), object fluents (each kept as a
predicate with the value as its last argument), preconditions and method
preconditions with negation, disjunction, equality and quantifiers,
conditional and ``forall`` effects, static constraints on task networks, an
initial task network with variables, a goal, and constant action costs.

The order of subtasks is one feature group of its own (:data:`TASK_ORDERS`):
the planner is a total-order planner today; once it searches partial orders,
adding ``"TASK_ORDER_PARTIAL"`` there widens the kind (the conversion already
passes a partial order through).
"""

from __future__ import annotations

# UP's feature names, grouped as in unified_planning.model.problem_kind
PROBLEM_CLASS = ("HIERARCHICAL",)
TASK_ORDERS = ("TASK_ORDER_TOTAL",)
HIERARCHICAL = (
    "METHOD_PRECONDITIONS",
    "TASK_NETWORK_CONSTRAINTS",
    "INITIAL_TASK_NETWORK_VARIABLES",
)
CONDITIONS = (
    "NEGATIVE_CONDITIONS",
    "DISJUNCTIVE_CONDITIONS",
    "EQUALITIES",
    "EXISTENTIAL_CONDITIONS",
    "UNIVERSAL_CONDITIONS",
)
EFFECTS = ("CONDITIONAL_EFFECTS", "FORALL_EFFECTS")
TYPING = ("FLAT_TYPING", "HIERARCHICAL_TYPING")
FLUENTS = ("OBJECT_FLUENTS",)
# a cost is a number per action (the operator's cost); the plan's cost is their
# sum, and the plan length is that sum with every cost 1
METRICS = (
    "ACTIONS_COST",
    "PLAN_LENGTH",
    "INT_NUMBERS_IN_ACTIONS_COST",
    "REAL_NUMBERS_IN_ACTIONS_COST",
)

FEATURES = (
    PROBLEM_CLASS + TASK_ORDERS + HIERARCHICAL + CONDITIONS + EFFECTS + TYPING + FLUENTS + METRICS
)


def supported_kind():
    """The ``ProblemKind`` of :data:`FEATURES` (UP's latest kind version)."""
    from unified_planning.model import ProblemKind
    from unified_planning.model.problem_kind_versioning import LATEST_PROBLEM_KIND_VERSION

    return ProblemKind(set(FEATURES), version=LATEST_PROBLEM_KIND_VERSION)


def unsupported_features(kind) -> list[str]:
    """The features of a problem's kind that htn does not support, sorted."""
    return sorted(set(kind.features) - set(FEATURES))
