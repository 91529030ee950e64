"""The project's bus: typed pub/sub, request/reply and presence over Zenoh.

Why a wrapper: every service needs the same few guarantees — messages are
validated before user code sees them (a subscription with a ``schema`` hands
its handler the stream's typed message from :mod:`shared.messages`, checked
all the way down, so no service walks an unchecked map; a queryable answers
with a reply type from there too, and an asker may read it as one), a bad
message is logged and counted
instead of crashing the receiver, Zenoh's threads are never blocked by user
code, every query is finalised, requests time out cleanly, and closing leaves
no thread behind. Samples wait in zenoh's own channels (ring channels for
streams where only the newest matters) and handlers run on one worker thread
per subscription.
"""

from __future__ import annotations

import logging
import threading
from collections import Counter
from collections.abc import Callable
from typing import Any, TypeVar, overload

import zenoh
import zenoh.ext as zext

from shared.codec import MessageError, decode, encode
from shared.config import SessionOptions, enforces_access_control, zenoh_config
from shared.denials import log_access_denials
from shared.keys import Keys
from shared.messages import TYPES, read, typed, wire
from shared.messages import Message as Typed

log = logging.getLogger("hfpbd.bus")

Message = dict[str, Any]
Handler = Callable[[Message], None]
R = TypeVar("R", bound=Typed)


class BusTimeout(TimeoutError):
    """No reply arrived in time: the service is probably not running."""


class RemoteError(RuntimeError):
    """The service answered the request with an error message."""


class MalformedReply(RemoteError):
    """The service answered with a reply that does not fit the reply's type: as good as an error from it."""


class Publisher:
    """Publishes typed messages (``shared.messages``) on one key."""

    def __init__(self, raw: Any, key: str) -> None:
        self._raw = raw
        self.key = key

    def put(self, message: Typed) -> None:
        self._raw.put(encode(message))

    def undeclare(self) -> None:
        self._raw.undeclare()


class _Worker:
    """Drains one zenoh channel on a daemon thread, running a handler per item.

    The channel lives in zenoh (Rust), so zenoh's threads never run Python
    user code; undeclaring the entity closes the channel and ends the loop.
    """

    def __init__(self, name: str, run: Callable[[Any], None]) -> None:
        self._run = run
        self._name = name
        self.thread: threading.Thread | None = None

    def start(self, source: Any) -> None:
        self.thread = threading.Thread(target=self._loop, args=(source,), name=self._name, daemon=True)
        self.thread.start()

    def _loop(self, source: Any) -> None:
        for item in source:
            try:
                self._run(item)
            except Exception:  # a handler bug must not kill the subscription
                log.exception("handler on %s failed", self._name)

    def join(self, timeout: float = 2.0) -> None:
        if self.thread is not None and threading.current_thread() is not self.thread:
            self.thread.join(timeout)


def _reason(exc: BaseException) -> str:
    """The message of an exception; KeyError's repr-quoting is dropped."""
    if isinstance(exc, KeyError) and exc.args:
        return str(exc.args[0])
    return str(exc) or type(exc).__name__


def _channel(latest_only: bool, capacity: int) -> Any:
    """Ring channels keep only the newest items (clouds, state); FIFO ones keep all, applying back-pressure."""
    return zenoh.handlers.RingChannel(1) if latest_only else zenoh.handlers.FifoChannel(capacity)


class Bus:
    """One Zenoh session with the project's conventions.

    Use as a context manager (``with Bus(options) as bus:``) so the session is
    always closed; an unclosed Zenoh session can hang interpreter exit.
    """

    def __init__(self, options: SessionOptions) -> None:
        self.options = options
        self.keys = Keys(options.namespace)
        for warning in options.warnings:
            log.warning(warning)
        if enforces_access_control(options):
            log_access_denials()
        self.session = zenoh.open(zenoh_config(options))
        self.rejected: Counter[str] = Counter()
        self._declared: list[Any] = []
        self._workers: list[_Worker] = []
        self._lock = threading.Lock()
        self._closed = False

    # -- lifecycle ---------------------------------------------------------
    def __enter__(self) -> Bus:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Undeclare everything, stop the workers, close the session."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            declared, self._declared = self._declared, []
            workers, self._workers = self._workers, []
        for entity in reversed(declared):
            try:
                entity.undeclare()
            except Exception:  # already gone with its session
                log.debug("undeclare failed", exc_info=True)
        for worker in workers:
            worker.join()
        self.session.close()

    def _keep(self, entity: Any) -> Any:
        with self._lock:
            self._declared.append(entity)
        return entity

    def _drain(self, name: str, entity: Any, run: Callable[[Any], None]) -> None:
        """Keep ``entity`` (a declared zenoh object with a channel) and drain it on a worker."""
        worker = _Worker(name, run)
        self._keep(entity)
        with self._lock:
            self._workers.append(worker)
        worker.start(entity)

    # -- publish -----------------------------------------------------------
    def publisher(self, key: str, *, cached: bool = False, large: bool = False) -> Publisher:
        """Declare a publisher.

        ``cached`` keeps the last sample for late joiners (subscribers with
        ``history=True`` get it at once). ``large`` blocks instead of dropping
        under congestion: multi-megabyte fragmented samples can otherwise
        vanish silently.
        """
        congestion = zenoh.CongestionControl.BLOCK if large else zenoh.CongestionControl.DROP
        raw: zenoh.Publisher | zext.AdvancedPublisher
        if cached:
            raw = zext.declare_advanced_publisher(
                self.session,
                key,
                congestion_control=congestion,
                cache=zext.CacheConfig(max_samples=1),
                publisher_detection=True,
            )
        else:
            raw = self.session.declare_publisher(key, congestion_control=congestion)
        return Publisher(self._keep(raw), key)

    def publish(self, key: str, message: Typed) -> None:
        """Publish once without declaring a publisher (dialog lines, events)."""
        self.session.put(key, encode(message))

    # -- subscribe ---------------------------------------------------------
    @overload
    def subscribe(
        self,
        key: str,
        handler: Handler,
        *,
        schema: None = None,
        latest_only: bool = False,
        history: bool = False,
        capacity: int = 1024,
    ) -> None: ...

    @overload
    def subscribe(
        self,
        key: str,
        handler: Callable[[Any], None],
        *,
        schema: str,
        latest_only: bool = False,
        history: bool = False,
        capacity: int = 1024,
    ) -> None: ...

    def subscribe(
        self,
        key: str,
        handler: Callable[[Any], None],
        *,
        schema: str | None = None,
        latest_only: bool = False,
        history: bool = False,
        capacity: int = 1024,
    ) -> None:
        """Call ``handler(message)`` on a worker thread for each valid sample.

        With a ``schema`` (a stream name of :data:`shared.messages.TYPES`)
        ``message`` is that stream's typed object, decoded once; a sample
        that does not fit it anywhere, nested fields included, is logged and
        counted in :attr:`rejected` and never reaches the handler. Without
        one it is the decoded map, with the sample's key under ``_key``.
        ``latest_only`` keeps just the newest pending sample (streams where
        only the present matters); ``history`` also receives the last cached
        sample of each cached publisher, now and when one appears later.
        """
        if schema is not None and schema not in TYPES:
            raise ValueError(f"no message type for schema {schema!r}")

        def run(sample: zenoh.Sample) -> None:
            if sample.kind != zenoh.SampleKind.PUT:
                return
            sample_key = str(sample.key_expr)
            try:
                message = decode(sample.payload.to_bytes())
                received = typed(schema, message) if schema is not None else message
            except MessageError as exc:
                self.rejected[key] += 1
                log.warning("rejected message on %s: %s", sample_key, exc)
                return
            if schema is None:
                message.setdefault("_key", sample_key)
            handler(received)

        channel = _channel(latest_only, capacity)
        sub: zenoh.Subscriber[Any] | zext.AdvancedSubscriber[Any]
        if history:
            sub = zext.declare_advanced_subscriber(
                self.session, key, channel, history=zext.HistoryConfig(detect_late_publishers=True, max_samples=1)
            )
        else:
            sub = self.session.declare_subscriber(key, channel)
        self._drain(f"sub:{key}", sub, run)

    # -- request / reply ---------------------------------------------------
    @overload
    def serve(
        self, key: str, handler: Callable[[Message], Typed], *, request: None = None, capacity: int = 64
    ) -> None: ...

    @overload
    def serve(self, key: str, handler: Callable[[R], Typed], *, request: type[R], capacity: int = 64) -> None: ...

    def serve(
        self,
        key: str,
        handler: Callable[[Any], Typed],
        *,
        request: type[Typed] | None = None,
        capacity: int = 64,
    ) -> None:
        """Answer queries on ``key`` with ``handler(request) -> reply``, a typed reply of :mod:`shared.messages`.

        With a ``request`` type the handler gets the request as that type; one
        that does not fit is refused as malformed (logged and counted in
        :attr:`rejected`) before the handler sees it. Without one it gets the
        decoded map. Runs on a worker thread; every query is finalised, and a
        handler exception becomes an error reply carrying its message, so the
        asker gets a reason rather than a timeout. ``ValueError`` and
        ``LookupError`` mean "refused" and are logged in one line; anything
        else is a bug and is logged with its traceback.
        """

        def run(query: zenoh.Query) -> None:
            try:
                try:
                    asked = decode(query.payload.to_bytes()) if query.payload is not None else {}
                    reply = handler(read(request, asked) if request is not None else asked)
                except MessageError as exc:
                    self.rejected[key] += 1
                    log.warning("rejected request on %s: %s", key, exc)
                    query.reply_err(encode({"error": f"malformed request: {exc}"}))
                    return
                except (ValueError, LookupError) as exc:  # a refused request: the asker's mistake
                    log.warning("refused request on %s: %s", key, exc)
                    query.reply_err(encode({"error": _reason(exc)}))
                    return
                except Exception as exc:  # a bug: keep the traceback for the log
                    log.exception("request handler on %s failed", key)
                    query.reply_err(encode({"error": _reason(exc)}))
                    return
                query.reply(query.key_expr, encode(wire(reply)))
            finally:
                query.drop()

        self._drain(f"serve:{key}", self.session.declare_queryable(key, _channel(False, capacity)), run)

    @overload
    def request(
        self, key: str, message: Typed | Message | None = None, *, reply: None = None, timeout: float = 5.0
    ) -> Message: ...

    @overload
    def request(
        self, key: str, message: Typed | Message | None = None, *, reply: type[R], timeout: float = 5.0
    ) -> R: ...

    def request(
        self,
        key: str,
        message: Typed | Message | None = None,
        *,
        reply: type[Typed] | None = None,
        timeout: float = 5.0,
    ) -> Any:
        """Send a query and return the first reply; raise on error or timeout.

        With a ``reply`` type the answer is that type, checked all the way
        down: an answer that does not fit raises :class:`MalformedReply`
        naming the field (a :class:`RemoteError`, which askers already
        handle), so an asker never reads a field the service did not send.
        Without one it is the decoded map.
        """
        replies = self.session.get(key, payload=encode(message or {}), timeout=timeout)
        for answer in replies:
            if answer.ok is not None:
                decoded = decode(answer.ok.payload.to_bytes())
                if reply is None:
                    return decoded
                try:
                    return read(reply, decoded)
                except MessageError as exc:
                    raise MalformedReply(f"malformed reply on {key}: {exc}") from None
            refusal = answer.err
            if refusal is None:
                continue
            try:
                error = decode(refusal.payload.to_bytes()).get("error", "unknown error")
            except MessageError:
                error = refusal.payload.to_string()
            raise RemoteError(str(error))
        raise BusTimeout(f"no reply on {key} within {timeout:g} s (is the service running?)")

    # -- presence ----------------------------------------------------------
    def declare_alive(self, service: str) -> None:
        """Announce that ``service`` is up; the token vanishes when the process dies."""
        self._keep(self.session.liveliness().declare_token(self.keys.alive(service)))

    def watch_alive(self, handler: Callable[[str, bool], None]) -> None:
        """Call ``handler(service, alive)`` for every service appearing or vanishing."""

        def run(sample: zenoh.Sample) -> None:
            handler(self.keys.service_of(str(sample.key_expr)), sample.kind == zenoh.SampleKind.PUT)

        subscriber = self.session.liveliness().declare_subscriber(
            self.keys.alive_all, _channel(False, 256), history=True
        )
        self._drain("alive", subscriber, run)

    def alive_services(self, timeout: float = 1.0) -> set[str]:
        """The services whose liveliness token is up right now."""
        replies = self.session.liveliness().get(self.keys.alive_all, timeout=timeout)
        return {self.keys.service_of(str(r.ok.key_expr)) for r in replies if r.ok is not None}
