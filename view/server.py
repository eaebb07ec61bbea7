"""The local web server of the view: Starlette on uvicorn, in a thread of its own.

It serves the page (``/``), its assets (``/static/...``, shipped inside the
package: the page loads nothing from elsewhere) and one WebSocket per page
(``/ws``), which the :class:`~htn.view.hub.Hub` feeds. Every request must
carry the run's random token (``?token=...``, in the URL that is printed);
any other gets 403. It binds 127.0.0.1 unless told otherwise.

The server's event loop runs in a daemon thread; the robot's thread only
hands records to the hub. The port is bound before the thread starts, so a
port in use is an input error before the run begins.
"""

from __future__ import annotations

import asyncio
import html
import ipaddress
import secrets
import socket
import threading
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs

from htn.jshop.language.errors import HtnError

from .hub import Hub

STATIC = Path(__file__).resolve().parent / "static"
HEADERS = {
    "Cache-Control": "no-store",
    "Referrer-Policy": "no-referrer",  # the token stays in this page's URL
    "X-Content-Type-Options": "nosniff",
    "Content-Security-Policy": "default-src 'self'; img-src 'self' blob:; "
    "connect-src 'self'; style-src 'self'; script-src 'self'",
}
FORBIDDEN = "403 forbidden: open the URL that htn printed (it holds this run's token)\n"


def is_loopback(host: str) -> bool:
    """Is ``host`` only reachable from this machine?"""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class TokenGate:
    """ASGI middleware: only requests whose query has the token pass; others
    get 403 (a WebSocket is refused before its handshake, which is a 403 too)."""

    def __init__(self, app, token: str):
        self.app, self.token = app, token

    async def __call__(self, scope, receive, send):
        if scope["type"] in ("http", "websocket"):
            query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
            given = query.get("token", [""])[0]
            if not secrets.compare_digest(given.encode(), self.token.encode()):
                if scope["type"] == "websocket":
                    await send({"type": "websocket.close", "code": 1008})
                    return
                from starlette.responses import PlainTextResponse

                await PlainTextResponse(FORBIDDEN, status_code=403, headers=HEADERS)(
                    scope, receive, send
                )
                return
        await self.app(scope, receive, send)


def make_app(source, token: str):
    """The ASGI application: the page, its assets, its WebSocket, behind the
    token; ``source.hub`` is the hub a new page is served from (a server may
    move on to another run's hub, :meth:`ViewServer.switch`)."""
    from starlette.applications import Starlette
    from starlette.responses import HTMLResponse
    from starlette.routing import Mount, Route, WebSocketRoute
    from starlette.staticfiles import StaticFiles
    from starlette.websockets import WebSocketDisconnect

    page = (STATIC / "index.html").read_text(encoding="utf-8")

    async def index(request):
        text = page.replace("{{TOKEN}}", html.escape(token)).replace(
            "{{TITLE}}", html.escape(source.hub.title or "htn view")
        )
        return HTMLResponse(text, headers=HEADERS)

    async def websocket(ws):
        await ws.accept()
        hub = source.hub

        async def drain():  # what the page says, until it goes
            try:
                while True:
                    hub.page_said(await ws.receive_text())
            except (WebSocketDisconnect, RuntimeError):
                pass

        sender = asyncio.ensure_future(hub.serve(ws.send_text, ws.send_bytes))
        reader = asyncio.ensure_future(drain())
        try:
            await asyncio.wait({sender, reader}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            for task in (sender, reader):
                task.cancel()
            await asyncio.gather(sender, reader, return_exceptions=True)
        if sender.done() and not sender.cancelled() and sender.exception() is None:
            try:
                await ws.close(code=1000)  # the hub closed: the view is over
            except (WebSocketDisconnect, RuntimeError):
                pass  # the page went first (starlette turns a send to it into this)

    class Static(StaticFiles):
        async def get_response(self, path, scope):
            response = await super().get_response(path, scope)
            response.headers.update(HEADERS)
            return response

    app = Starlette(
        routes=[
            Route("/", index),
            WebSocketRoute("/ws", websocket),
            Mount("/static", Static(directory=str(STATIC)), name="static"),
        ]
    )
    return TokenGate(app, token)


class ViewServer:
    """The server of one hub on ``host``:``port`` (0: a free port)."""

    def __init__(self, hub: Hub, host: str = "127.0.0.1", port: int = 0):
        self.hub, self.host = hub, host
        self.token = secrets.token_urlsafe(18)
        self.sock = _listen(host, port)
        self.port = self.sock.getsockname()[1]
        self._server: Any | None = None  # the uvicorn.Server, once started
        self.loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        host = self.host
        if host in ("0.0.0.0", "::", ""):
            host = socket.gethostname()
        elif ":" in host:
            host = f"[{host}]"
        return f"http://{host}:{self.port}/?token={self.token}"

    def start(self, timeout: float = 10.0) -> ViewServer:
        import uvicorn

        config = uvicorn.Config(
            make_app(self, self.token),
            log_level="warning",
            access_log=False,
            lifespan="off",
            ws=_ws_protocol(),
            timeout_graceful_shutdown=1,
            log_config=None,
            ws_per_message_deflate=False,
        )  # loopback: nothing to save
        self._server = uvicorn.Server(config)
        ready = threading.Event()

        def serve():
            loop = asyncio.new_event_loop()
            asyncio.set_event_loop(loop)
            self.hub.loop = self.loop = loop
            loop.call_soon(ready.set)
            try:
                loop.run_until_complete(self._server.serve(sockets=[self.sock]))
            finally:
                self.hub.loop = self.loop = None
                loop.close()

        self._thread = threading.Thread(target=serve, name="htn-view", daemon=True)
        self._thread.start()
        if not ready.wait(timeout):
            raise HtnError("the view's web server did not start")
        return self

    def switch(self, hub: Hub) -> None:
        """Serve ``hub`` from now on (the next goal of a node): the pages of
        the one before are told to load the page again."""
        old, hub.loop = self.hub, self.loop
        self.hub = hub
        old.close(next_goal=True)

    def close(self, timeout: float = 3.0) -> None:
        """Close the pages' connections and stop the server."""
        self.hub.close()
        if self._server is not None:
            self._server.should_exit = True
        if self._thread is not None:
            self._thread.join(timeout)
            if self._thread.is_alive() and self._server is not None:
                self._server.force_exit = True
                self._thread.join(timeout)
        try:
            self.sock.close()
        except OSError:
            pass


def _ws_protocol() -> str:
    """uvicorn's WebSocket protocol on the websockets library: its sans-I/O
    implementation where this uvicorn has it (the older one is deprecated)."""
    from uvicorn.config import WS_PROTOCOLS

    return "websockets-sansio" if "websockets-sansio" in WS_PROTOCOLS else "websockets"


def _listen(host: str, port: int) -> socket.socket:
    """A listening socket on ``host``:``port``; a bad host or a port in use is an input error."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except socket.gaierror as exc:
        raise HtnError(
            f"cannot serve the view on {host}: no such address ({exc.strerror})"
        ) from exc
    family, _, _, _, address = infos[0]
    sock = socket.socket(family, socket.SOCK_STREAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(16)
    except OSError as exc:
        sock.close()
        raise HtnError(f"cannot serve the view on {host} port {port}: {exc.strerror}") from exc
    sock.setblocking(False)
    return sock
