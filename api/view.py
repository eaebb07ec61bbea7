"""The view use cases: the browser view of a finished log (``htn view LOG``)
and of a run going on (``htn run PLAN --view``).

* :func:`read_view_log` then :func:`serve_log` - a log of ``htn run --log``
  (or one goal of a rosbag2 bag of ``htn ros record``, :mod:`htn.view.bag`),
  read and checked, then served as a page with a scrubber; the
  :class:`LogPage` returned holds its URL and stays up until
  :meth:`LogPage.close`;
* :func:`start_live_view` - the view of a run, started before the robot
  moves: the :class:`htn.view.live.RunView` returned is given the run with
  ``attach(log, dispatcher, robot)``, waits for a page with
  ``wait_for_page()`` and is ended with ``close()``;
* :func:`exposure_warning` - what to warn of when the page is served on an
  address other machines can reach.

The page is served on ``host``:``port`` (127.0.0.1 and a free port unless
told otherwise), its URL holding a random token. The server (Starlette on
uvicorn) is the ``view`` extra: :mod:`htn.view` is imported inside these
functions only, and without the extra they raise an
:class:`~htn.jshop.language.errors.HtnError` naming it. A log that cannot be
read, a bad address or a port in use are ``HtnError`` s too. Nothing here
prints or waits for Ctrl-C: the caller keeps the page up as long as it likes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from htn.jshop.language.errors import HtnError

from .extras import require_extra

if TYPE_CHECKING:
    from htn.view.live import GoalsView, RunView
    from htn.view.server import ViewServer

DEFAULT_HOST = "127.0.0.1"


@dataclass
class ViewLog:
    """A log of ``htn run --log``, read and checked for the page."""

    path: str
    records: list[dict[str, Any]] = field(repr=False)
    warning: str | None = None  # a last line cut short, left out
    note: str | None = None  # a bag's: which of its goals this is

    @property
    def events(self) -> int:
        """How many events the page shows."""
        return len(self.records)


def read_view_log(log_file: str, what: str = "htn view", goal: int | None = None) -> ViewLog:
    """The log ``log_file`` read for :func:`serve_log`: every line a JSON
    event, the first its header, else an input error at that line; a last
    line cut short is left out with a warning (:attr:`ViewLog.warning`).
    A rosbag2 bag of ``htn ros record`` (a folder, a ``.db3`` or ``.mcap``
    file) gives the records of its goal ``goal`` (1-based; default: the
    last), which :attr:`ViewLog.note` names. ``what`` names what needs the
    view extra in the error without it."""
    require_extra("view", what)
    from htn.view.bag import is_bag, read_bag

    if is_bag(log_file):
        bag = read_bag(log_file, goal)
        return ViewLog(str(log_file), bag.records, bag.warning, bag.note)
    if goal is not None:
        raise HtnError(
            "--goal chooses a goal of a rosbag2 bag (htn ros record); a log holds one run",
            str(log_file),
        )
    from htn.view.model import read_log

    records, warning = read_log(str(log_file))
    return ViewLog(str(log_file), records, warning)


class LogPage:
    """The page of a finished log, served until :meth:`close` (also as a
    context manager)."""

    def __init__(self, log: ViewLog, server: ViewServer) -> None:
        self.log, self.server = log, server

    @property
    def url(self) -> str:
        """The page's address, with its token."""
        return self.server.url

    @property
    def events(self) -> int:
        return self.log.events

    def close(self) -> None:
        """Close the pages' connections and stop the server."""
        self.server.close()

    def __enter__(self) -> LogPage:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def serve_log(
    log: ViewLog | str, host: str = DEFAULT_HOST, port: int = 0, what: str = "htn view"
) -> LogPage:
    """Serve the page of ``log`` (a :class:`ViewLog`, or the path of a log,
    read by :func:`read_view_log`) on ``host``:``port`` (0: a free port)."""
    if not isinstance(log, ViewLog):
        log = read_view_log(log, what)
    require_extra("view", what)
    from htn.view.hub import Hub
    from htn.view.model import page_records, title_of
    from htn.view.server import ViewServer

    hub = Hub("log", page_records(log.records), title=title_of(log.records[0]))
    return LogPage(log, ViewServer(hub, host, port).start())


def start_live_view(
    host: str = DEFAULT_HOST, port: int = 0, what: str = "htn run --view"
) -> RunView:
    """Start the view of a run on ``host``:``port``, before the robot moves:
    a started :class:`htn.view.live.RunView` (its ``url``; ``attach``,
    ``wait_for_page``, ``close``)."""
    require_extra("view", what)
    from htn.view.live import RunView

    return RunView(host, port).start()


def start_goals_view(
    host: str = DEFAULT_HOST, port: int = 0, what: str = "htn ros node --view"
) -> GoalsView:
    """Start the view of a robot node's goals on ``host``:``port``: a started
    :class:`htn.view.live.GoalsView` (its ``url``; ``event`` for each event
    of the goal being run, ``close``)."""
    require_extra("view", what)
    from htn.view.live import GoalsView

    return GoalsView(host, port).start()


def exposure_warning(host: str) -> str | None:
    """What to warn of when serving on ``host``: None for an address only
    this machine reaches (loopback), else that anyone with the URL can watch."""
    from htn.view.server import is_loopback

    if is_loopback(host):
        return None
    return (
        f"the view is served on {host}, reachable from other machines: "
        f"anyone with its URL (the token) can watch"
    )
