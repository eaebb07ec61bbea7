"""An rclpy action client that never drops its server's answer.

rclpy's :class:`~rclpy.action.ActionClient` (7.1 on Jazzy) sends a request
and only then records its sequence number. A thread that spins the client's
executor meanwhile may take the answer in between, find no request of that
number, log "Ignoring unexpected goal response" and drop it: the goal's
future never completes (ros2/rclpy#1123, fixed upstream in later releases).
:class:`~htn.ros.robot.RosRobot` spins in a thread of its own and sends from
the dispatcher's, so it met this now and then ("did not answer the goal").

:class:`OrderedActionClient` takes one lock around each send and its
recording, and around handling what the executor took, so an answer is
handled only once its request is known.
"""

from __future__ import annotations

import threading

from rclpy.action import ActionClient


class OrderedActionClient(ActionClient):
    """:class:`~rclpy.action.ActionClient` whose sends and answers are ordered."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._order = threading.RLock()  # a done callback may send (a cancel)

    def send_goal_async(self, goal, feedback_callback=None, goal_uuid=None):
        with self._order:
            return super().send_goal_async(goal, feedback_callback, goal_uuid)

    def _cancel_goal_async(self, goal_handle):
        with self._order:
            return super()._cancel_goal_async(goal_handle)

    def _get_result_async(self, goal_handle):
        with self._order:
            return super()._get_result_async(goal_handle)

    async def execute(self, taken_data):
        # it sets the futures' results and calls the feedback callback (a
        # plain function here: nothing is awaited while the lock is held)
        with self._order:
            await super().execute(taken_data)
