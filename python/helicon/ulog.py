"""Flight logs in PX4's ULog format (``.ulg``), read into NumPy arrays."""

from __future__ import annotations

import os
from typing import Any, Dict, Union

import numpy as np

from . import _helicon

__all__ = ["read", "read_all"]


def read(path: Union[str, "os.PathLike[str]"]) -> Dict[str, Dict[str, np.ndarray]]:
    """Every topic of a ULog file as ``{topic: {field: ndarray}}``.

    Fields are flattened as ``helicon log export`` and pyulog name them
    (``outer.inner``, ``name[i]``), ``timestamp`` (µs, uint64) first. Types:
    ``float``/``double`` → float64, ``uint64_t`` → uint64, ``bool`` → bool,
    other integers and ``char`` → int64. Instance 0 of a topic is keyed by
    its name, instance k > 0 as ``name_k``; topics that logged nothing are
    left out. A truncated file (a writer killed mid-message) gives every
    complete message (see :func:`read_all` for whether it was).
    """
    return _helicon.ulog_read(os.fspath(path))["topics"]


def read_all(path: Union[str, "os.PathLike[str]"]) -> Dict[str, Any]:
    """The whole log: ``{"topics", "info", "parameters", "start_timestamp_us", "truncated"}``.

    ``topics`` as :func:`read`; ``info`` the INFO messages as text;
    ``parameters`` the parameters (numbers; a change during the log
    replaces the initial value).
    """
    return _helicon.ulog_read(os.fspath(path))
