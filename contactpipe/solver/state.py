"""The march's state after its last completed instant: what the next instant starts from,
and what a checkpoint keeps to resume from it (:meth:`State.arrays`, :meth:`State.restore`)."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .normal import NormalResult

__all__ = ["State"]


@dataclass
class State:
    """The march after its last completed instant: what the next instant starts from.

    Attributes
    ----------
    p : ndarray (N1, N2)
        Pressure [Pa].
    q : ndarray (2, N1, N2)
        Shear traction [Pa].
    u : ndarray (3, N1, N2)
        Relative surface displacement [m].
    s : ndarray (2, N1, N2)
        Accumulated slip [m].
    omega : ndarray (3,)
        Rigid-body displacement of body 1 relative to body 2 [m].
    phi : ndarray (3,)
        Rigid-body rotation of body 1 relative to body 2 (φ1, φ2, φ3) [rad].
    dissipation : float
        Frictional energy dissipated so far [J].
    memories : list
        The viscoelastic memory of each body (indenter, half-space), None without one.
    normal : NormalResult or None
        The last normal solution (reused while the normal problem does not change).
    k : int
        The last completed instant (-1 before the first).
    dq : ndarray (2, N1, N2)
        The last instant's shear increment [Pa], which continues the shear along a
        straight load path (:func:`contactpipe.solver.warm_start.continued_start`).
    dp : ndarray (N1, N2)
        The last instant's pressure increment [Pa], which continues the joint solve's
        pressure start alike.
    """

    p: np.ndarray
    q: np.ndarray
    u: np.ndarray
    s: np.ndarray
    omega: np.ndarray
    dissipation: float
    memories: list
    normal: NormalResult | None = None
    k: int = -1
    phi: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    dq: np.ndarray | None = None
    dp: np.ndarray | None = None

    def __post_init__(self):
        if self.dq is None:
            self.dq = np.zeros_like(self.q)
        if self.dp is None:
            self.dp = np.zeros_like(self.p)

    @classmethod
    def initial(cls, shape, memories) -> State:
        """The unloaded state on a grid of ``shape`` cells."""
        n1, n2 = shape
        return cls(np.zeros((n1, n2)), np.zeros((2, n1, n2)), np.zeros((3, n1, n2)),
                   np.zeros((2, n1, n2)), np.zeros(3), 0.0, list(memories))

    @property
    def motion(self) -> np.ndarray:
        """The six rigid motions reached (ω3, ω1, ω2, φ1, φ2, φ3) [m, rad]."""
        return np.concatenate([self.omega[[2, 0, 1]], self.phi])

    def arrays(self) -> dict:
        """The arrays a checkpoint stores (the last normal solution is not kept)."""
        out = {"p": self.p, "q": self.q, "u": self.u, "s": self.s, "omega": self.omega,
               "phi": self.phi, "dissipation": np.array(self.dissipation), "dq": self.dq,
               "dp": self.dp}
        for i, m in enumerate(self.memories):
            if m is not None:
                out.update({f"mem{i}_{key}": np.asarray(v) for key, v in m.state().items()})
        return out

    def restore(self, arrays: dict, k: int) -> None:
        """Take the state a checkpoint stored after instant ``k``.

        Raises
        ------
        ValueError, KeyError
            An array is missing or has the wrong shape.
        """
        n1, n2 = self.p.shape
        shapes = {"p": (n1, n2), "q": (2, n1, n2), "u": (3, n1, n2), "s": (2, n1, n2),
                  "omega": (3,), "phi": (3,), "dissipation": ()}
        # the increments may be missing: a checkpoint written before they were kept; the
        # next instant then starts from q and p as they are (a start only; the instants
        # agree within the tolerance)
        increments = {"dq": (2, n1, n2), "dp": (n1, n2)}
        for key, shape in {**shapes, **increments}.items():
            if (key in arrays or key in shapes) and np.shape(arrays[key]) != shape:
                raise ValueError(f"{key} has shape {np.shape(arrays[key])}, expected {shape}")
        self.p, self.q, self.u, self.s = (np.asarray(arrays[key], dtype=float)
                                          for key in ("p", "q", "u", "s"))
        self.omega = np.array(arrays["omega"], dtype=float)
        self.phi = np.array(arrays["phi"], dtype=float)
        self.dissipation = float(arrays["dissipation"])
        self.dq, self.dp = (np.array(arrays[key], dtype=float) if key in arrays
                            else np.zeros(shape) for key, shape in increments.items())
        for i, m in enumerate(self.memories):
            if m is not None:
                m.load_state({key[len(f"mem{i}_"):]: v for key, v in arrays.items()
                              if key.startswith(f"mem{i}_")})
        self.normal, self.k = None, int(k)
