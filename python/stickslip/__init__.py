"""stickslip: a client of stickslipd, the periodic orbits, families, maps,
basins and sweeps of the two-mass stick-slip oscillator of M. Pascal (2011).

    import stickslip
    c = stickslip.Client("http://127.0.0.1:8080")
    ans = c.orbit(params={"chi": 0.2, "eta": 4, "us": 0.0724,
                          "ur": 0.6178, "V": 1}, kind="overshoot")

Standard library only; ``stickslip.arrays`` turns answers into numpy arrays
and pandas frames when those are installed.
"""

from .client import Client, Lines
from .errors import (BadFraming, BadRequest, BodyTooLarge,
                     ClientClosedRequest, ContentTooLarge, InternalError,
                     InvalidJSON, InvalidType, InvalidValue, LimitExceeded,
                     MethodNotAllowed, MissingField, NoConvergence, NotFound,
                     OutOfMemory, Overloaded, ProblemError, RequestOverLimit,
                     ShuttingDown, StickslipError, StoreUnavailable,
                     TransportError,
                     UnknownField, Unavailable, Unprocessable,
                     UnsupportedMediaType)
from .jobs import Job, JobFailed

__version__ = "0.4.0"

__all__ = [
    "Client", "Lines", "Job", "JobFailed", "StickslipError",
    "TransportError", "ProblemError", "BadRequest", "InvalidJSON",
    "BadFraming", "NotFound", "MethodNotAllowed", "ContentTooLarge",
    "BodyTooLarge", "UnsupportedMediaType", "Unprocessable", "InvalidType",
    "InvalidValue", "MissingField", "UnknownField", "NoConvergence",
    "LimitExceeded", "RequestOverLimit", "ClientClosedRequest",
    "InternalError", "Unavailable", "Overloaded", "OutOfMemory",
    "ShuttingDown", "StoreUnavailable",
]
