"""Euclidean norms of small float arrays with numpy's arithmetic but without its dispatch
(``np.linalg.norm`` costs µs of argument handling per call, more than the sums on these sizes):
the same operations, so the same bits (tested against ``np.linalg.norm``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def row_norms(x: np.ndarray, keepdims: bool = False) -> np.ndarray:
    """``np.linalg.norm(x, axis=1, keepdims=keepdims)`` of a real 2-D array, bit for bit (numpy
    takes the square root of ``add.reduce(x * x)`` along the rows)."""
    squares: Any = np.add.reduce  # (numpy's stubs do not type keepdims as a bool)
    out: np.ndarray = np.sqrt(squares(x * x, axis=1, keepdims=keepdims))
    return out


def vector_norm(v: np.ndarray) -> float:
    """Euclidean norm of a 1-D float64 array: ``float(np.linalg.norm(v))`` bit for bit (numpy
    takes the square root of ``v.dot(v)`` over a contiguous copy of a strided view)."""
    if not v.flags.c_contiguous:
        v = v.ravel(order="K")
    return math.sqrt(v.dot(v))
