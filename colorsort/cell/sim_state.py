"""The sim-state codec: everything that makes an instant replayable, as one float64 vector.

The vector's layout is written once, in ``SEGMENTS``, and versioned: a change to it bumps
``VERSION``, which the collector stores beside each dataset (``meta/colorsort.json``).

====================  ===================  ==========================================================
segment               length               what
====================  ===================  ==========================================================
``mujoco``            ``mj_stateSize``     MuJoCo's state (``MJ_STATE_SPEC``): time, qpos, qvel,
                                           controls, active equalities, mocap, the solver's warm start
``boxes``             4 x pool size        per pooled box: colour (index in ``config.ALL_COLORS``, -1 while
                                           parked), status (index in ``BoxStatus``), bin (index in
                                           ``BIN_COLORS`` or -1), serial
``held``              1                    the sealed box's pool index, or -1
``weld``              ``mjNEQDATA``        the seal's weld ``eq_data`` (zeros when none)
``belt_pass``         1                    the belt-pass command, 0 or 1
``belt_running``      1                    0 or 1
``belt_travel``       1                    [m] the belt's encoder: distance its surface travelled
``next_spawn_time``   1                    [s]
``next_serial``       1
``clock``             1                    the env's clock [s]
``rng``               10                   the env's PCG64 generator, in 32-bit words
====================  ===================  ==========================================================

Applied forces (``qfrc_applied``, ``xfrc_applied``) are left out: ColorSort never sets them.

This module is the codec only: the plant's parts give their state (``Plant.get_state``), the env adds
its clock and generator (``ColorSort.get_sim_state``), and ``CellState`` packs them into the vector.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import mujoco
import numpy as np

from colorsort.cell.plant import MJ_STATE_SPEC, PlantState
from colorsort.errors import ConfigError

VERSION = 2  # 2: belt_travel (the belt's encoder) added
RNG_STATE_SIZE = 10  # a PCG64 generator's state and increment (4 x 32 bits each), then its uint32 buffer
PLANT_SCALARS = ("held", "belt_pass", "belt_running", "belt_travel", "next_spawn_time", "next_serial")


def rng_to_words(rng: np.random.Generator) -> np.ndarray:
    """A PCG64 generator's full state as 32-bit words (exact in float64)."""
    st = rng.bit_generator.state
    if st["bit_generator"] != "PCG64":
        raise ConfigError(f"Only PCG64 generators can be saved, not {st['bit_generator']}")
    words = [(v >> (32 * k)) & 0xFFFFFFFF for v in (st["state"]["state"], st["state"]["inc"]) for k in range(4)]
    return np.array(words + [st["has_uint32"], st["uinteger"]], dtype=np.float64)


def rng_from_words(words: np.ndarray) -> np.random.Generator:
    """The generator ``rng_to_words`` saved."""
    w = [int(x) for x in words]
    state, inc = (sum(w[i + k] << (32 * k) for k in range(4)) for i in (0, 4))
    gen = np.random.Generator(np.random.PCG64())
    gen.bit_generator.state = {"bit_generator": "PCG64", "state": {"state": state, "inc": inc},
                               "has_uint32": w[8], "uinteger": w[9]}
    return gen


@dataclass(frozen=True)
class SimStateLayout:
    """Where each segment lies in the vector, for a model with ``mujoco_size`` state numbers and
    ``pool_size`` boxes."""

    mujoco_size: int
    pool_size: int

    @classmethod
    def of(cls, model: mujoco.MjModel, pool_size: int) -> SimStateLayout:
        return cls(mujoco.mj_stateSize(model, MJ_STATE_SPEC), pool_size)

    @property
    def lengths(self) -> dict[str, int]:
        """Segment name -> length, in order (the table in the module docstring)."""
        return {"mujoco": self.mujoco_size, "boxes": 4 * self.pool_size, "held": 1, "weld": mujoco.mjNEQDATA,
                **{name: 1 for name in PLANT_SCALARS[1:]}, "clock": 1, "rng": RNG_STATE_SIZE}

    @property
    def slices(self) -> dict[str, slice]:
        out, start = {}, 0
        for name, n in self.lengths.items():
            out[name] = slice(start, start + n)
            start += n
        return out

    @property
    def size(self) -> int:
        return sum(self.lengths.values())

    def describe(self) -> dict:
        """The layout as JSON-ready data: version and [start, stop) per segment."""
        return {"version": VERSION, "segments": {k: [s.start, s.stop] for k, s in self.slices.items()}}


@dataclass
class CellState:
    """One instant of the cell: the plant's state, the env's clock [s] and its generator (as words)."""

    plant: PlantState
    clock: float  # [s]
    rng: np.ndarray  # (RNG_STATE_SIZE,) words: ``rng_to_words``

    def pack(self, layout: SimStateLayout) -> np.ndarray:
        values = {**{f.name: getattr(self.plant, f.name) for f in fields(PlantState)},
                  "clock": self.clock, "rng": self.rng}
        out = np.empty(layout.size, np.float64)
        for name, s in layout.slices.items():
            out[s] = np.ravel(np.asarray(values[name], dtype=np.float64))
        return out

    @classmethod
    def unpack(cls, vector: np.ndarray, layout: SimStateLayout) -> CellState:
        vector = np.asarray(vector, dtype=np.float64)
        if vector.shape != (layout.size,):
            raise ConfigError(f"Expected a state of shape ({layout.size},), got {vector.shape}: "
                             "was it saved with another robot or pool size?")
        s = layout.slices
        scalar = {name: vector[s[name]][0] for name in (*PLANT_SCALARS, "clock")}
        plant = PlantState(mujoco=vector[s["mujoco"]], boxes=vector[s["boxes"]].reshape(-1, 4).astype(int),
                           held=int(scalar["held"]), weld=vector[s["weld"]], belt_pass=bool(scalar["belt_pass"]),
                           belt_running=bool(scalar["belt_running"]), belt_travel=float(scalar["belt_travel"]),
                           next_spawn_time=float(scalar["next_spawn_time"]), next_serial=int(scalar["next_serial"]))
        return cls(plant, clock=float(scalar["clock"]), rng=vector[s["rng"]])
