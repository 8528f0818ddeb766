"""semslam: visual semantic SLAM with landmarks (maps, trajectories, evaluation, a SLAM system).

The compiled part is the extension semslam._semslam (python/module.cc); everything it defines is re-exported here,
so `import semslam; semslam.load_map(...)` is the interface. semslam.city maps many drives on Dask distributed
(`python3 -m semslam.city --help`)."""

from . import _semslam
from ._semslam import *  # noqa: F401,F403
from ._semslam import __version__, commit  # noqa: F401

# The classes and exceptions say they are semslam's (help(), repr of types, tracebacks), as before the package.
for _name in dir(_semslam):
    _value = getattr(_semslam, _name)
    if isinstance(_value, type) and getattr(_value, "__module__", None) == _semslam.__name__:
        try:
            _value.__module__ = __name__
        except (AttributeError, TypeError):
            pass
del _name, _value
