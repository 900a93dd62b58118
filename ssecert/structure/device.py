"""Screening sensor sets on an accelerator: the single-precision tier of ``ColexScreen``
written against the Python array API standard, so that PyTorch or CuPy run it on a GPU and
numpy runs the very same code in the test suite.

An accelerator only proves: where its single-precision factorization of a Gramian minus the
screening margin succeeds, LAPACK's float64 factorization of the Gramian succeeds too, and its
smallest pivot is at least the accelerator's (``ssecert.numerics.linalg.single_precision_margin``; the
proof holds for any IEEE single-precision arithmetic that factors column by column as
``cholesky_batch_last`` does, whatever the order of its sums and with or without fused
multiply-adds).  Every set it does not prove, every failure and every proxy of the sets closest
to breaking is LAPACK's on the CPU, as without it: the answer does not depend on the device.

The matrices it factors are those of the CPU tier, bit for bit: the single-precision level of
partial sums (computed on the CPU, sent once per range) plus each block's top, summed in single
precision on the CPU and added on the device.  ``device="numpy"`` runs this module's code on
the CPU, so that the test suite checks it (and array-api-strict checks that it uses the
standard only) on machines without a GPU.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

__all__ = ["DEVICES", "DeviceUnavailable", "resolve_device"]

#: the devices ``device=`` accepts: ``"cpu"`` (numpy and LAPACK, the default), ``"cuda"``
#: (PyTorch with CUDA, else CuPy) and ``"numpy"`` (the accelerator's code run by numpy on the
#: CPU: slower than ``"cpu"``, for testing that code on a machine without a GPU)
DEVICES = ("cpu", "cuda", "numpy")

# sets screened together on a device: large enough to keep a GPU busy (about 400 MB of
# single-precision 10 x 10 matrices), ...
DEVICE_BATCH_SETS = 1 << 20
# ... and a range of fewer sets stays on the CPU, whose bound and batches are faster there
DEVICE_MIN_SETS = 1 << 14


class DeviceUnavailable(RuntimeError):
    """The device asked for cannot be used here: its array library is not installed, or it has
    no GPU."""


def _check(name: str) -> str:
    if name not in DEVICES:
        raise ValueError(f"device must be one of {', '.join(DEVICES)}, got {name!r}")
    return name


def resolve_device(device: str | None) -> str | None:
    """The device name to screen sets on (None: the CPU path), checked to be usable here.

    Raises
    ------
    ValueError
        For a name not in ``DEVICES``.
    DeviceUnavailable
        With what to install, when the device cannot be used.
    """
    if device is None or _check(device) == "cpu":
        return None
    device_kernel(device)  # imports its library once, raising if it cannot run
    return device


@functools.cache
def device_kernel(name: str) -> DeviceKernel:
    """The kernel of a device name, built once per process (its library imported once)."""
    return DeviceKernel(*_namespace(_check(name)), name=name)


def _namespace(name: str) -> tuple[Any, Any]:
    """(array namespace, device) of a device name."""
    if name == "numpy":
        return _compat("numpy") or np, "cpu"
    if _compat("numpy") is None:
        raise DeviceUnavailable(
            "screening on cuda needs array-api-compat and PyTorch with CUDA or CuPy; install "
            "them with: python -m pip install 'ssecert[gpu]' torch"
        )
    problems = []
    try:
        import torch

        if torch.cuda.is_available():
            return _compat("torch"), torch.device("cuda")
        problems.append("PyTorch sees no CUDA device")
    except ImportError:
        problems.append("PyTorch is not installed")
    try:
        import cupy

        cupy.cuda.runtime.getDeviceCount()
        return _compat("cupy"), None
    except ImportError:
        problems.append("CuPy is not installed")
    except Exception as exc:  # CUDA's own errors: no driver, no device
        problems.append(f"CuPy finds no CUDA device ({exc})")
    raise DeviceUnavailable(
        f"no CUDA device to screen on: {'; '.join(problems)} (install PyTorch with CUDA, "
        "python -m pip install torch, or CuPy)"
    )


def _compat(library: str) -> Any:
    """array-api-compat's namespace for a library, None when array-api-compat is missing."""
    import importlib

    try:
        return importlib.import_module(f"array_api_compat.{library}")
    except ImportError:
        return None


def cholesky_diagonal(xp: Any, A: Any) -> Any:
    """The diagonal of the Cholesky factors of a batch stored with the batch last.

    The algorithm of ``ssecert.numerics.linalg.cholesky_batch_last`` (left-looking,
    column by column, each column scaled by the reciprocal of its pivot), in
    the array API standard only and without writing into views; the
    products of the earlier columns are summed by one reduction per column
    (a few launches per column on a device, whatever n; the margin's error
    bound holds for any order of the sums, so the proof is the same, though
    the last bits may differ from the CPU's).  A matrix that is not positive
    definite gets a NaN or a non-positive entry.

    Parameters
    ----------
    xp : array namespace
    A : array, shape (n, n, N)
        The matrices ``A[:, :, b]`` (their lower triangles are read).

    Returns
    -------
    array, shape (n, N)
    """
    n = A.shape[0]
    columns: list[Any] = []  # columns[k]: rows k..n-1 of the factor's column k
    diagonal = []
    for j in range(n):
        column = A[j:, j, :]
        if j:
            # rows j..n-1 of the earlier columns, side by side: (n - j, j, N)
            below = xp.stack([c[j - k :, :] for k, c in enumerate(columns)], axis=1)
            column = column - xp.sum(below * below[0:1, :, :], axis=1)
        root = xp.sqrt(column[0, :])
        diagonal.append(root)
        if j + 1 < n:
            columns.append(xp.concat([root[None, :], column[1:, :] * (1.0 / root)[None, :]]))
    return xp.stack(diagonal)


class DeviceKernel:
    """The single-precision tier of ``ColexScreen`` on one device.

    Parameters
    ----------
    xp : array namespace
    device : object
        The namespace's device (None: its default).
    name : str
        What the user asked for (``DEVICES``).
    """

    def __init__(self, xp: Any, device: Any, *, name: str) -> None:
        self.xp, self.device, self.name = xp, device, name

    def _put(self, array: np.ndarray) -> Any:
        return self.xp.asarray(array, device=self.device)

    def load(self, level: np.ndarray) -> Any:
        """The single-precision level of partial sums on the device (a copy the caller keeps
        for as long as it screens that level: the kernel keeps none, so that one caller's
        level is never taken for another's)."""
        return self._put(np.ascontiguousarray(level))

    def screen(
        self,
        level: Any,
        rows: np.ndarray,
        offsets: np.ndarray,
        totals: np.ndarray | None,
        size: int,
    ) -> DeviceBatch:
        """Factor the ``size`` single-precision matrices of a batch's pieces on the device.

        Parameters
        ----------
        level : device array of float32, shape (n, n, M)
            The single-precision level of partial sums (the screening margin taken off), as
            ``load`` put it on the device.
        rows : ndarray of int, shape (P,)
            The first row of each piece in the batch, ascending (the first is 0).
        offsets : ndarray of int, shape (P,)
            Row r of piece i is the level's matrix ``r + offsets[i]`` ...
        totals : ndarray of float32, shape (n, n, P), or None
            ... plus ``totals[:, :, i]``, the single-precision sum of the piece's top (None:
            no tops, the level is the whole sum).
        size : int

        Returns
        -------
        DeviceBatch
            The results, kept on the device.
        """
        xp = self.xp
        # each row's piece found on the device from the pieces alone (a few numbers per piece
        # sent, not one index per set)
        positions = xp.arange(size, device=self.device)
        piece = xp.searchsorted(self._put(rows), positions, side="right") - 1
        matrices = xp.take(level, positions + xp.take(self._put(offsets), piece), axis=2)
        if totals is not None:
            matrices = matrices + xp.take(self._put(totals), piece, axis=2)
        with np.errstate(all="ignore"):  # NaN pivots of the failures (numpy underneath)
            diagonal = cholesky_diagonal(xp, matrices)
            smallest = xp.min(diagonal, axis=0)
            passed = (smallest > 0) & xp.isfinite(xp.sum(diagonal, axis=0))
        return DeviceBatch(xp, passed, smallest)


class DeviceBatch:
    """A batch factored on the device, its results kept there: the host asks for the few
    rows it needs (the failures, the sets closest to breaking), not for a number per set.

    Parameters
    ----------
    xp : array namespace
    passed : device array of bool, shape (N,)
        Every pivot positive and finite.
    smallest : device array of float32, shape (N,)
        The smallest pivot (meaningful where passed).
    """

    def __init__(self, xp: Any, passed: Any, smallest: Any) -> None:
        self.xp, self.passed, self.smallest = xp, passed, smallest
        self._low: tuple[float, Any] | None = None

    def failed(self) -> np.ndarray:
        """The rows that did not pass, ascending."""
        xp = self.xp
        return _to_numpy(xp.nonzero(xp.logical_not(self.passed))[0]).astype(np.int64)

    def _bounds(self, shift: float) -> Any:
        """Each passed row's lower bound of its proxy, ``fl(fl(s^2) + shift)`` for its
        smallest single-precision pivot s (at most LAPACK's pivot, so at most its proxy),
        +inf for the others."""
        if self._low is None or self._low[0] != shift:
            xp = self.xp
            with np.errstate(all="ignore"):
                s = xp.astype(self.smallest, xp.float64)
                low = xp.where(self.passed, s * s + shift, xp.full_like(s, xp.inf))
            self._low = (shift, low)
        return self._low[1]

    def below(
        self, threshold: float, shift: float, most: int | None = None
    ) -> tuple[np.ndarray, np.ndarray, bool]:
        """(rows, their bounds, False): the passed rows whose bound is at most ``threshold``,
        ascending; when there are more than ``most``, the ``most`` of the smallest bounds
        and True."""
        xp = self.xp
        low = self._bounds(shift)
        rows = xp.nonzero(low <= threshold)[0]
        values = xp.take(low, rows)
        truncated = most is not None and rows.shape[0] > most
        if truncated:
            smallest = xp.argsort(values, stable=True)[:most]
            rows, values = xp.take(rows, smallest), xp.take(values, smallest)
        values = _to_numpy(values)
        rows = _to_numpy(rows).astype(np.int64)
        order = np.argsort(rows)
        return rows[order], values[order], truncated


def _to_numpy(x: Any) -> np.ndarray:
    """A device array as a numpy array on the host."""
    if isinstance(x, np.ndarray):
        return x
    module = type(x).__module__
    if module.startswith("torch"):
        return x.cpu().numpy()
    if module.startswith("cupy"):
        return x.get()
    return np.from_dlpack(x)
