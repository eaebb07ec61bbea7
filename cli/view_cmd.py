"""``htn view run.jsonl`` (or a bag of ``htn ros record``), and the ``--view``
options of ``htn run``: the browser view.

The page (served by :mod:`htn.view.server` on 127.0.0.1 unless told otherwise)
shows the task tree with each node's outcome, the running action, the camera
of a PyBullet robot and every event; ``htn view`` shows a finished log the
same way, with a scrubber. Its URL, with the run's token, is printed on
stderr as one line ``view: http://127.0.0.1:PORT/?token=...``.
"""

from __future__ import annotations

import time

import click

from htn.api.view import exposure_warning, read_view_log, serve_log, start_live_view

from .options import PORT, Count, current_stops

HOST_HELP = (
    "Address to serve the view on (default 127.0.0.1: this machine only; any "
    "other address lets other machines reach it, with the token, and is warned of)"
)


def view_options(command):
    """The ``--view`` options of ``htn run``."""
    for option in reversed(
        [
            click.option(
                "--view",
                is_flag=True,
                help="Watch the run in a browser: serve a live page (task tree, running "
                "action, camera, events) and print its URL; the page stays up "
                "after the run until Ctrl-C (the 'view' extra).",
            ),
            click.option("--view-host", metavar="HOST", default="127.0.0.1", help=HOST_HELP + "."),
            click.option(
                "--view-port",
                metavar="PORT",
                type=PORT,
                default=0,
                help="Port of the view (default: a free one).",
            ),
            click.option(
                "--view-wait",
                is_flag=True,
                help="With --view: start the robot only once a page has connected, so "
                "the whole run is watched live.",
            ),
        ]
    ):
        command = option(command)
    return command


def start_run_view(host: str, port: int, what: str = "htn run --view"):
    """Start the view of a run (before the robot moves) and print its URL."""
    view = start_live_view(host, port, what)
    _announce(view.url, host)
    return view


def wait_for_page(view) -> None:
    click.echo(
        "view: waiting for a page to connect before the robot starts (Ctrl-C to stop)", err=True
    )
    view.wait_for_page()


def keep_up(view, listen=None) -> None:
    """After the run: the page stays until Ctrl-C (or SIGTERM). ``listen``
    turns those signals on again (they were held off while the run ended)."""
    try:
        if listen is not None:
            listen()
        click.echo(f"view: the run is over; the page stays at {view.url} until Ctrl-C", err=True)
        _serve_until_interrupted()
    except KeyboardInterrupt:
        current_stops().consume()
    view.close()


def _announce(url: str, host: str) -> None:
    warning = exposure_warning(host)
    if warning:
        click.echo(f"warning: {warning}", err=True)
    click.echo(f"view: {url}", err=True)


def _serve_until_interrupted() -> None:
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        current_stops().consume()  # Ctrl-C is how the page is closed: the exit code is not its


@click.command("view")
@click.argument("log_file", type=click.Path())
@click.option("--host", default="127.0.0.1", metavar="HOST", help=HOST_HELP + ".")
@click.option(
    "--port", type=PORT, default=0, metavar="PORT", help="Port to serve on (default: a free one)."
)
@click.option(
    "--goal",
    type=Count(1),
    metavar="N",
    help="Of a rosbag2 bag holding several goals: the Nth (default: the last).",
)
def view(log_file, host, port, goal):
    """Show the log of a run (htn run --log FILE.jsonl) in a browser; or a
    goal of a rosbag2 bag that htn ros record wrote (its folder, or its
    .db3 or .mcap file).

    Serves a page, on this machine only unless --host says otherwise, and
    prints its URL (with a random token: requests without it get 403). The
    page shows the task tree with each node's outcome (retries and faults
    marked on their nodes, repaired subtrees shown replaced beside the
    grafted ones), the action at each event and every event; the scrubber
    plays the run, steps one event back or forward, jumps to the next fault,
    and shows the tree as it was at that event. Ctrl-C stops the server
    (exit code 0).

    \b
    Examples:
      htn run plan.txt --sim --faults slip=0.3 --log run.jsonl
      htn view run.jsonl
      htn view run.jsonl --host 0.0.0.0 --port 8765   # from another machine
      htn view session.bag --goal 2                    # htn ros record session.bag
    """
    log = read_view_log(log_file, "htn view", goal)
    if log.warning:
        click.echo(f"warning: {log.warning}", err=True)
    page = serve_log(log, host, port, "htn view")
    try:
        _announce(page.url, host)
        of = f" ({log.note})" if log.note else ""
        click.echo(
            f"view: {log.events} events of {log_file}{of}; Ctrl-C stops the server", err=True
        )
        _serve_until_interrupted()
    except KeyboardInterrupt:  # Ctrl-C is how a server stops: not an error
        current_stops().consume()
    finally:
        page.close()
