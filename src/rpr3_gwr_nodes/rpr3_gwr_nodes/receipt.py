"""How long a service request has waited, for deadlines that count from its
reception.

rclpy hands a service callback the request alone; the time DDS received it
(``rmw_service_info_t.received_timestamp``, on the system clock) stays with
the executor.  A request that arrives while every executor thread is busy
waits in the service's reader, and that wait is part of the caller's: a
:class:`ReceiptExecutor` takes requests as rclpy's executor does
(``Executor._take_service``) and keeps the reception time where the
callback reads it, :func:`request_age`.
"""

import contextvars
import time

from rclpy.exceptions import InvalidHandle
from rclpy.executors import await_or_execute

from .executors import BoundedExecutor

__all__ = ["ReceiptExecutor", "request_age"]

_RECEIVED_NS = contextvars.ContextVar("received_ns", default=0)


def request_age():
    """Seconds since DDS received the request the calling service callback
    serves; 0 outside a :class:`ReceiptExecutor`'s service callbacks, or
    when the transport gives no reception time."""
    received = _RECEIVED_NS.get()
    if not received:
        return 0.0
    return max(0.0, (time.time_ns() - received) * 1e-9)


class ReceiptExecutor(BoundedExecutor):
    """A :class:`~.executors.BoundedExecutor` whose service callbacks know,
    through :func:`request_age`, when their request was received."""

    def _take_service(self, srv):
        try:
            with srv.handle:
                request, header = srv.handle.service_take_request(srv.srv_type.Request)
        except InvalidHandle:
            # Destroyed meanwhile: the executor's own take gives up as well.
            return None
        if header is None:
            return None

        async def _execute():
            token = _RECEIVED_NS.set(header.received_timestamp)
            try:
                response = await await_or_execute(srv.callback, request,
                                                  srv.srv_type.Response())
            finally:
                _RECEIVED_NS.reset(token)
            srv.send_response(response, header)
        return _execute
