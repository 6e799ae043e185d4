"""msgpack with numpy arrays, in openpi's encoding: an array travels as the map
{__ndarray__: True, data: raw bytes, dtype: numpy dtype string, shape: [...]}, a numpy scalar
as {__npgeneric__: True, data, dtype}. Object arrays are refused (never pickled)."""

from __future__ import annotations

import msgpack
import numpy as np


def _pack(obj):
    if isinstance(obj, np.ndarray | np.generic) and obj.dtype.kind in "VOc":
        raise ValueError(f"cannot send arrays of dtype {obj.dtype}")
    if isinstance(obj, np.ndarray):
        return {b"__ndarray__": True, b"data": np.ascontiguousarray(obj).tobytes(),
                b"dtype": obj.dtype.str, b"shape": list(obj.shape)}
    if isinstance(obj, np.generic):
        return {b"__npgeneric__": True, b"data": obj.item(), b"dtype": obj.dtype.str}
    return obj


def _unpack(obj):
    if b"__ndarray__" in obj:
        return np.frombuffer(obj[b"data"], dtype=np.dtype(obj[b"dtype"])).reshape(
            obj[b"shape"]).copy()
    if b"__npgeneric__" in obj:
        return np.dtype(obj[b"dtype"]).type(obj[b"data"])
    return obj


def packb(obj) -> bytes:
    return msgpack.packb(obj, default=_pack, use_bin_type=True)


def unpackb(data: bytes):
    return msgpack.unpackb(data, object_hook=_unpack, raw=False, strict_map_key=False)
