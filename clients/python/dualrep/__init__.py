"""dualrep's Python package: serve environments to a dualrep server (:mod:`dualrep.env`), drive
its REST API (:class:`Client`), and answer its queries from Python (:class:`Trainer`)."""

from .client import ApiError, Client
from .trainer import Trainer

__all__ = ["ApiError", "Client", "Trainer"]
__version__ = "0.1.0"
