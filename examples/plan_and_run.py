"""Plan a bundled problem with htn's Python API, run the plan on the symbolic
robot with injected faults and repair, and print what happens.

Run it from anywhere once htn is installed (the core install is enough):
    python plan_and_run.py
"""

import htn

DOMAIN = htn.EXAMPLES / "domains" / "domestic.jshop"
PROBLEM = htn.EXAMPLES / "problems" / "bring_object.jshop"


def show(event):
    """Called with every event of the run as it happens."""
    if event["event"] in ("verified", "retrying", "aborted", "replanned", "fault"):
        print(f"{event['step'] or '':>2} {event['event']:<10} {event['action'] or ''}")


plans = htn.plan(DOMAIN, PROBLEM, plans=3)  # a stream of plans, each with its task tree
found = list(plans)
print(f"{len(found)} plans found in {plans.stats['expansions']} expansions")
for p in found:  # the same steps, different decompositions (the planning paper's Table 1)
    grasp = next(n for n in p.tree.walk() if n.name == "grasp_object")
    print(f"plan {p.index + 1}: {len(p.steps)} steps, {grasp.path} by {grasp.branch}")

result = htn.run(
    found[1],
    domain=plans.domain,
    problem=plans.problem,
    robot="symbolic",
    faults="effect=0.3",
    seed=3,
    replan=True,
    on_event=show,
)
s = result.summary
print(
    f"{s.result}: {s.verified} of {s.steps} steps verified, {s.retries} retries, "
    f"{s.replans} replans"
)
