"""Who the studio answers: its own ``Host`` and ``Origin``, and its token when it has one.

One rule for both servers. The API (:class:`GuardMiddleware`) and the scene server
(:class:`studio.web._serve.SceneGuard`, a :class:`SiteRule`) accept:

- a ``Host`` header that names this studio (loopback names, ``--host``, ``--allow-host``): a
  page on another site that reaches 127.0.0.1 through DNS rebinding names its own host;
- requests whose ``Origin`` is absent (command-line clients, scripts) or one of the studio's own
  pages. For the API that is Jupyter Server's rule: a state-changing request (POST, PUT, PATCH,
  DELETE) is refused when its ``Origin``, or failing that its ``Referer``, is another site; a
  websocket is refused from another site whatever its method; a read of the API (``GET
  /api/...``: an export, a figure, a rollout can cost minutes of CPU) is refused when its
  ``Origin`` is another site or the browser marks it ``Sec-Fetch-Site: cross-site`` or
  ``same-site`` (an ``<img>`` or a link another page loads sends no ``Origin``; a page of
  another program on this machine, on another port, is the same site but not the studio);
- when a token is set (required beyond loopback), only requests carrying it: ``?token=`` once
  (the link printed at start; the answer sets a cookie the page's later requests carry), the
  cookie, or an ``Authorization: token <token>`` (or ``Bearer``) header for scripts.
"""

from __future__ import annotations

import hmac
import logging
from collections.abc import Iterable
from http.cookies import SimpleCookie
from urllib.parse import parse_qs, urlsplit

from fastapi.responses import JSONResponse
from starlette.types import ASGIApp, Message, Receive, Scope, Send

log = logging.getLogger(__name__)

STATE_CHANGING_METHODS = frozenset({"POST", "PUT", "PATCH", "DELETE"})
"""Methods that change something: refused from another site's page."""
READ_METHODS = frozenset({"GET", "HEAD"})
"""Methods that only read: refused from another site's page under :data:`WORK_PREFIX`."""
WORK_PREFIX = "/api/"
"""Paths whose reads do work (exports, figures, rollouts): the page itself and its files are not."""
API_TOKEN_COOKIE = "teach-studio-{port}"
"""Cookie that carries the token to the API after the page was opened with ``?token=``."""
DEFAULT_PORTS = {"http": 80, "https": 443}


def _hostname(netloc: str | None) -> str | None:
    if not netloc:
        return None
    name = urlsplit(f"//{netloc}").hostname
    return name.lower() if name else None


def token_matches(given: str | None, token: str) -> bool:
    """Whether ``given`` is ``token`` (compared in constant time)."""
    return bool(given) and hmac.compare_digest(str(given).encode(), token.encode())


def cookie_value(header: str | None, name: str) -> str | None:
    """The value of cookie ``name`` in a ``Cookie`` header (None when absent or malformed)."""
    if not header:
        return None
    jar: SimpleCookie = SimpleCookie()
    try:
        jar.load(header)
    except Exception:  # a malformed cookie header is just no cookie
        return None
    morsel = jar.get(name)
    return morsel.value if morsel is not None else None


class SiteRule:
    """The host names and ports that make a ``Host`` or ``Origin`` this studio's, and its token.

    Args:
        hosts: host names accepted in ``Host`` and ``Origin`` (:meth:`Settings.trusted_hosts`).
        ports: ports an ``Origin`` may carry (the servers' own).
        token: when set, requests must carry it (see the module docstring).
        cookie_port: the port named in the token cookie (default: the smallest of ``ports``).
    """

    cookie_name = API_TOKEN_COOKIE

    def __init__(
        self,
        hosts: Iterable[str],
        ports: Iterable[int],
        token: str | None = None,
        cookie_port: int | None = None,
    ) -> None:
        self.hosts = {h.strip("[]").lower() for h in hosts}
        self.ports = set(ports)
        self.token = token or None
        self.cookie_port = (
            cookie_port if cookie_port is not None else (min(self.ports) if self.ports else 0)
        )

    @property
    def cookie(self) -> str:
        """The token cookie's name."""
        return self.cookie_name.format(port=self.cookie_port)

    def host_ok(self, host: str | None) -> bool:
        """Whether a ``Host`` header names this studio."""
        name = _hostname(host)
        return name is not None and name in self.hosts

    def origin_ok(self, origin: str | None, host: str | None = None) -> bool:
        """Whether an ``Origin`` (or a ``Referer``) is absent or one of the studio's own pages.

        Args:
            origin: the header's value (a ``Referer`` is a full URL: its scheme and host count).
            host: the request's ``Host`` header, already checked by :meth:`host_ok`; a page
                served from exactly that host and port is the studio's own (Jupyter's rule),
                whatever port the studio really listens on behind a tunnel.
        """
        if origin is None:
            return True
        parts = urlsplit(origin.strip())
        if parts.scheme not in DEFAULT_PORTS or not parts.hostname:
            return False  # "null" (sandboxed frames, file://), or not a web page at all
        try:
            port = parts.port or DEFAULT_PORTS[parts.scheme]
        except ValueError:
            return False
        if host is not None and self.host_ok(host) and parts.netloc.lower() == host.lower():
            return True
        return parts.hostname.lower() in self.hosts and port in self.ports

    def token_ok(self, path: str, cookie: str | None) -> tuple[bool, bool]:
        """``(allowed, from_query)``: the token matches (query or cookie), or none is needed."""
        if self.token is None:
            return True, False
        query = urlsplit(path).query
        return self.token_ok_parts(query, cookie, None)

    def token_ok_parts(
        self, query: str, cookie: str | None, authorization: str | None
    ) -> tuple[bool, bool]:
        """:meth:`token_ok` from a query string, a ``Cookie`` and an ``Authorization`` header."""
        if self.token is None:
            return True, False
        given = parse_qs(query).get("token", [""])[0]
        if token_matches(given, self.token):
            return True, True
        if token_matches(cookie_value(cookie, self.cookie), self.token):
            return True, False
        if authorization:
            scheme, _, value = authorization.partition(" ")
            if scheme.lower() in ("token", "bearer") and token_matches(value.strip(), self.token):
                return True, False
        return False, False

    def set_cookie_header(self) -> str:
        """The ``Set-Cookie`` value that lets the page's later requests carry the token."""
        return f"{self.cookie}={self.token}; Path=/; HttpOnly; SameSite=Strict"


class GuardMiddleware:
    """The API's guard: the token (when set) on every request, and no change from another site.

    Runs inside the ``Host`` check (Starlette's ``TrustedHostMiddleware``), so the ``Host`` it
    sees already names this studio.

    Args:
        app: the app to guard.
        rule: hosts, ports and token (from :class:`~studio.web.Settings`).
    """

    def __init__(self, app: ASGIApp, rule: SiteRule) -> None:
        self.app = app
        self.rule = rule
        self.refused = 0

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}
        allowed, from_query = self.rule.token_ok_parts(
            scope.get("query_string", b"").decode("latin-1"),
            headers.get("cookie"),
            headers.get("authorization"),
        )
        if not allowed:
            self.refused += 1
            await self._refuse(
                scope,
                receive,
                send,
                "This studio needs its token; open the link with ?token= that the studio printed when it started, or send the header Authorization: token <token>.",
            )
            return
        method = scope.get("method", "GET").upper()
        if scope["type"] == "http" and method in READ_METHODS:
            if scope["path"].startswith(WORK_PREFIX) and self._cross_site_read(headers):
                self.refused += 1
                log.warning("Refused %s %s from another site.", method, scope["path"])
                await self._refuse(
                    scope,
                    receive,
                    send,
                    "This request comes from another site's page; only the studio's own page may ask the studio for work, so open it in the studio's page or from a client that sends no Origin.",
                )
                return
        elif scope["type"] == "websocket" or method in STATE_CHANGING_METHODS:
            source = headers.get("origin")
            if source is None:
                source = headers.get("referer")
            if not self.rule.origin_ok(source, headers.get("host")):
                self.refused += 1
                log.warning("Refused %s %s from another site (%s).", method, scope["path"], source)
                await self._refuse(
                    scope,
                    receive,
                    send,
                    f"This request comes from another site ({source}); only the studio's own page may change the studio, so use the studio's page or a client that sends no Origin.",
                )
                return
        if from_query:
            await self.app(scope, receive, self._with_cookie(send))
        else:
            await self.app(scope, receive, send)

    def _cross_site_read(self, headers: dict[str, str]) -> bool:
        """Whether a read comes from another site's page: a foreign ``Origin`` (a script's
        ``fetch``), or the browser's own ``Sec-Fetch-Site`` (an image, a link), ``cross-site`` or
        ``same-site``: another port of this machine (a local program's page) is the same site,
        and only ``same-origin`` (the studio's page) or ``none`` (typed, a bookmark) is the
        studio's."""
        if headers.get("sec-fetch-site", "").strip().lower() in ("cross-site", "same-site"):
            return True
        return not self.rule.origin_ok(headers.get("origin"), headers.get("host"))

    def _with_cookie(self, send: Send) -> Send:
        async def send_with_cookie(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                headers.append((b"set-cookie", self.rule.set_cookie_header().encode("latin-1")))
                message = {**message, "headers": headers}
            await send(message)

        return send_with_cookie

    @staticmethod
    async def _refuse(scope: Scope, receive: Receive, send: Send, detail: str) -> None:
        if scope["type"] == "websocket":
            await send({"type": "websocket.close", "code": 1008})
            return
        await JSONResponse({"detail": detail}, status_code=403)(scope, receive, send)
