"""msgpack with numpy arrays, in openpi's encoding: an array travels as the map
{__ndarray__: True, data: raw bytes, dtype: numpy dtype string, shape: [...]}, a numpy scalar
as {__npgeneric__: True, data, dtype}. Object and structured arrays are refused both ways
(never pickled)."""

from __future__ import annotations

import msgpack
import numpy as np

REFUSED_KINDS = "OV"  # object and structured/void dtypes: never decoded from the wire


class WireError(ValueError):
    """Bytes that are not a message of the protocol."""


class MessageTooBig(ConnectionError):
    """A message over the size limit of the end receiving it."""


def size_text(size: int) -> str:
    return f"{size} bytes" + (f" ({size / 2 ** 20:.1f} MiB)" if size >= 2 ** 20 else "")


def _pack(obj):
    if isinstance(obj, np.ndarray | np.generic) and obj.dtype.kind in REFUSED_KINDS + "c":
        raise ValueError(f"cannot send arrays of dtype {obj.dtype}")
    if isinstance(obj, np.ndarray):
        return {b"__ndarray__": True, b"data": np.ascontiguousarray(obj).tobytes(),
                b"dtype": obj.dtype.str, b"shape": list(obj.shape)}
    if isinstance(obj, np.generic):
        return {b"__npgeneric__": True, b"data": obj.item(), b"dtype": obj.dtype.str}
    return obj


def wire_dtype(name) -> np.dtype:
    """The numpy dtype a message names, refusing object and structured dtypes."""
    try:
        dtype = np.dtype(name if isinstance(name, str) else bytes(name).decode("ascii"))
    except (TypeError, ValueError, UnicodeDecodeError) as error:
        raise WireError(f"{name!r} is not a numpy dtype ({error})") from None
    if dtype.kind in REFUSED_KINDS:
        raise WireError(f"arrays of dtype {dtype} are refused")
    return dtype


def wire_array(data, dtype, shape) -> np.ndarray:
    """An array from its raw bytes, dtype name and shape, each checked."""
    dtype = wire_dtype(dtype)
    if not isinstance(data, bytes | bytearray):
        raise WireError("an array's data is not bytes")
    if not isinstance(shape, list | tuple) or not all(
            isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in shape):
        raise WireError(f"an array's shape {shape!r} is not a list of sizes")
    if int(np.prod(shape, dtype=np.int64)) * dtype.itemsize != len(data):
        raise WireError(f"an array of shape {list(shape)} and dtype {dtype} does not hold "
                        f"{len(data)} bytes")
    return np.frombuffer(data, dtype=dtype).reshape(shape).copy()


def _unpack(obj):
    if b"__ndarray__" in obj:
        return wire_array(obj.get(b"data"), obj.get(b"dtype"), obj.get(b"shape"))
    if b"__npgeneric__" in obj:
        dtype = wire_dtype(obj.get(b"dtype"))
        try:
            return dtype.type(obj.get(b"data"))
        except (TypeError, ValueError, OverflowError) as error:
            raise WireError(f"a numpy scalar of dtype {dtype} cannot hold "
                            f"{obj.get(b'data')!r}: {error}") from None
    return obj


def packb(obj) -> bytes:
    return msgpack.packb(obj, default=_pack, use_bin_type=True)


def unpackb(data: bytes):
    """The message in `data`; WireError says why bytes are not a msgpack-numpy message."""
    if not isinstance(data, bytes | bytearray):
        raise WireError(f"a {type(data).__name__} message, not binary msgpack")
    try:
        return msgpack.unpackb(data, object_hook=_unpack, raw=False, strict_map_key=False)
    except WireError:
        raise
    except Exception as error:  # msgpack's own errors (ExtraData, FormatError, StackError...)
        raise WireError(f"not msgpack: {type(error).__name__}: {error}") from None


SERVER_TEXT_LIMIT = 500  # characters of a server's own text (errors, metadata) quoted



def server_text(value) -> str:
    """A server's text as it is quoted in errors and records: one line, cut short."""
    text = " ".join(str(value).split())
    return text if len(text) <= SERVER_TEXT_LIMIT else text[:SERVER_TEXT_LIMIT] + " [...]"
