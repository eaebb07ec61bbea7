"""What the ROS tests that start nodes share: a ROS domain of each test
module's own per xdist worker (Fast DDS derives its ports from it; discovery
on this host only), and htn's interface packages built once, or the test
skipped with the reason where the ros extra, a compiler, cmake or the Python
headers are missing."""

from __future__ import annotations

import os
import re
import sys
from importlib.util import find_spec

import pytest

# each module's offset, so that two modules on the same worker never share a domain
OFFSETS = {
    "test_interfaces": 0,
    "test_record": 25,
    "test_node": 50,
    "test_robot": 75,
    "test_action_client": 95,
}


def environment(module: str) -> dict[str, str]:
    """This process's environment with this worker's domain for ``module``."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    domain = (int(re.sub(r"\D", "", worker) or 0) + OFFSETS[module]) % 102
    return {
        **os.environ,
        "ROS_DOMAIN_ID": str(domain),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
    }


def ready(module: str) -> dict[str, str]:
    """Skip without ROS; else build the interface packages (once per user)
    and return :func:`environment`."""
    if find_spec("rclpy") is None:
        pytest.skip("the ros extra is not installed (pip install -e '.[ros]'): no rclpy")
    from htn.ros import interfaces
    from htn.ros.interfaces import InterfaceBuildError

    try:
        for package in interfaces.SHIPPED:
            interfaces.locate(package) or interfaces.build(
                lambda message: print(message, file=sys.stderr), package
            )
    except InterfaceBuildError as error:
        if error.missing:
            pytest.skip(str(error))
        raise
    return environment(module)
