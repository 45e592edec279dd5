"""Serve any Gymnasium env, or your own class with ``reset``/``step``, or a robot, to dualrep.

>>> from dualrep.env import EnvServer, predicates
>>> @predicates(upright="pendulum upright")
... def scene(obs, action, info):
...     return {"upright": obs[0] > 0.9}
>>> server = EnvServer("Pendulum-v1", predicates=scene, port=5555)   # doctest: +SKIP
>>> server.serve_forever()                                          # doctest: +SKIP

or from a shell: ``python -m dualrep.env --gym Pendulum-v1 --predicates mymod:scene --port 5555``.
"""

from .adapter import FeatureFn, PredicateFn, SuccessFn, features, predicates
from .png import encode_png
from .protocol import PROTOCOL, ProtocolError, read_message, write_message
from .server import EnvServer, serve

__all__ = [
    "PROTOCOL",
    "EnvServer",
    "FeatureFn",
    "PredicateFn",
    "ProtocolError",
    "SuccessFn",
    "encode_png",
    "features",
    "predicates",
    "read_message",
    "serve",
    "write_message",
]
