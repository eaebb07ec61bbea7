"""The outcome of an action, one enum for every action and every report
(the planning paper, section 4; py_trees' status is the behaviour tree's own):

* ``finished``  - the action reports that it is done (feedback);
* ``verified``  - its monitor observed the expected effect in the world;
* ``failed``    - the action itself failed (internal error);
* ``aborted``   - it finished, but the monitor did not observe the effect, or
  a hold-monitor saw a condition break while it ran (it is then preempted);
* ``retrying``  - it will be tried again (up to the operator's retry limit).
"""

from __future__ import annotations

from enum import Enum


class Outcome(str, Enum):
    FINISHED = "finished"
    VERIFIED = "verified"
    FAILED = "failed"
    ABORTED = "aborted"
    RETRYING = "retrying"
