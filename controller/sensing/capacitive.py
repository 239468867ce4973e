"""Capacitive node model of a pressure-array sensor: what one taxel of a capacitive tactile array reads.

Each node is a parallel-plate capacitor: a square electrode pad of side w = pitch sqrt(fill_factor) (the rest of the
pitch x pitch cell is the gap between pads, which senses nothing) over a compressible dielectric of thickness d_0.
The chain from pressure to a reading, each effect switchable (``CapacitiveNode``):

1. Pad integration: the pad force F_pad = int_pad p dA (``controller.sensing.cell_force_operator`` clips the FEM's
   piecewise-linear field against the pad squares exactly); a uniform pressure gives F_pad = fill_factor x the
   cell's force. The top electrode is taken as rigid, so the pad sees its mean pressure p = F_pad / w^2.
2. Dielectric strain with saturation: eps(p) = eps_max (1 - exp(-p / (eps_max E_d))) for p >= 0 (initial slope
   1 / E_d, the compliance of the dielectric; the strain saturates at eps_max as the dielectric densifies), eps =
   p / E_d for p < 0 (tension; the FEM base pressure can be slightly negative beside a bump). ``nonlinear=False``:
   eps = p / E_d throughout.
3. Capacitance: C = eps0 eps_r w^2 / (d_0 (1 - eps)), so the change is dC = C_0 eps / (1 - eps), C_0 = c_area w^2
   with c_area = eps0 eps_r / d_0 the capacitance per pad area. (Plate-distance nonlinearity: sensitivity grows as
   the gap closes; with the dielectric's saturation the reading flattens at high pressure.)
4. Crosstalk: each node's dC gains ``crosstalk`` times the dC of each of its four neighbours (the coupling of
   row-column scanned arrays through shared lines and fringe fields).
5. Noise floor: Gaussian noise of ``noise_floor`` [pF] rms per node and frame (the converter's input noise).
   A built array (``realize``: one draw per node, kept for its life) also has a gain spread (each pad's dC times
   1 + ``gain_spread`` z, the dielectric's thickness and permittivity varying over the sheet), a baseline offset
   (``offset_spread`` [pF] rms) and a baseline that drifts at a rate of ``offset_drift`` [pF/s] rms (temperature,
   creep of the dielectric); all three enter dC before the converter, and the firmware knows none of them.
6. ADC quantization: a bipolar converter of ``adc_bits`` over +-``adc_range``/2 [pF] rounds dC to its step and
   clips it to its range (saturation of the converter). ``adc_bits=0``: no converter.
7. Read-out: the firmware inverts the nominal curve of 2-3 per node (without crosstalk, noise, gain or offset,
   which it cannot know) and reports the pad force F = p w^2 [N]: the reading the estimator receives, at
   ``sample_rate_hz``. Steps 2-7 are one compiled kernel (``_node_kernel.read_frame``), which the closed loop's
   plant calls too.

Defaults (``CapacitiveNode()``): eps_r = 3 over d_0 = 0.2 mm (c_area = 0.133 pF/mm^2, a silicone dielectric),
E_d = 0.2 MPa and eps_max = 0.5 (a soft dielectric: 0.5 %/kPa at small pressure), 2 % crosstalk to each
neighbour, 0.5 fF rms noise and a 16-bit converter over +-2 pF (61 aF steps) - values of the order of capacitive
tactile arrays read by sigma-delta capacitance-to-digital converters (~1 fF resolution). A 3 mm node with a
2.5 mm pad (C_0 = 0.83 pF) then reads a 1 kPa press as 4.1 fF, ~8 times its noise; a 1 mm node with a 0.5 mm pad
(C_0 = 0.033 pF) as 0.17 fF, a third of it: the trade-off between a fine pitch and its sensitivity that made the
paper choose 3 mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fem.validation import check_range

from ._node_kernel import capacitance_changes, node_law, pressures, read_frame

__all__ = ["CapacitiveNode", "NodeRealization", "VACUUM_PERMITTIVITY"]

VACUUM_PERMITTIVITY = 8.8541878128e-3     # pF/mm


@dataclass(frozen=True)
class CapacitiveNode:
    """Transducer and read-out of one capacitive node (module docstring); each effect has an "off" value.

    Parameters
    ----------
    relative_permittivity : float -- eps_r of the dielectric [-], > 0.
    dielectric_thickness : float -- d_0 [mm], > 0.
    dielectric_modulus : float -- E_d, the initial stiffness of the dielectric [MPa], > 0.
    max_strain : float -- eps_max, the strain the dielectric saturates at [-], in (0, 1).
    nonlinear : bool -- the saturating strain law and the 1 / (1 - eps) plate law; False: dC = C_0 p / E_d.
    crosstalk : float -- share of each 4-neighbour's dC added to a node's [-], in [0, 0.25); 0: off.
    noise_floor : float -- rms noise of dC per node and frame [pF], >= 0; 0: off.
    adc_bits : int -- converter resolution [bits], 0 (no converter) or 4 ... 32.
    adc_range : float -- span of the bipolar converter [pF] (dC from -range/2 to +range/2), > 0.
    gain_spread : float -- rms relative spread of the nodes' gains in a built array [-], in [0, 0.5].
    offset_spread : float -- rms baseline offset of a node in a built array [pF], >= 0.
    offset_drift : float -- rms rate of a node's baseline drift in a built array [pF/s], >= 0.
    """

    relative_permittivity: float = 3.0
    dielectric_thickness: float = 0.2
    dielectric_modulus: float = 0.2
    max_strain: float = 0.5
    nonlinear: bool = True
    crosstalk: float = 0.02
    noise_floor: float = 5e-4
    adc_bits: int = 16
    adc_range: float = 4.0
    gain_spread: float = 0.02
    offset_spread: float = 0.01
    offset_drift: float = 2e-5

    def __post_init__(self):
        check_range("relative_permittivity", self.relative_permittivity, 0.0, math.inf, "", True, True)
        check_range("dielectric_thickness", self.dielectric_thickness, 0.0, math.inf, "mm", True, True)
        check_range("dielectric_modulus", self.dielectric_modulus, 0.0, math.inf, "MPa", True, True)
        check_range("max_strain", self.max_strain, 0.0, 1.0, "", True, True)
        if not isinstance(self.nonlinear, bool):
            raise ValueError(f"nonlinear={self.nonlinear!r} must be True or False")
        check_range("crosstalk", self.crosstalk, 0.0, 0.25, "", high_open=True)
        check_range("noise_floor", self.noise_floor, 0.0, math.inf, "pF", high_open=True)
        if isinstance(self.adc_bits, bool) or int(self.adc_bits) != self.adc_bits or \
                not (self.adc_bits == 0 or 4 <= self.adc_bits <= 32):
            raise ValueError(f"adc_bits={self.adc_bits!r} must be 0 (no converter) or an integer in [4, 32]")
        check_range("adc_range", self.adc_range, 0.0, math.inf, "pF", True, True)
        check_range("gain_spread", self.gain_spread, 0.0, 0.5)
        check_range("offset_spread", self.offset_spread, 0.0, math.inf, "pF", high_open=True)
        check_range("offset_drift", self.offset_drift, 0.0, math.inf, "pF/s", high_open=True)

    @classmethod
    def ideal(cls) -> "CapacitiveNode":
        """Every effect off: a linear, noise-free, unquantized pad (the pad integral alone)."""
        return cls(nonlinear=False, crosstalk=0.0, noise_floor=0.0, adc_bits=0, gain_spread=0.0, offset_spread=0.0,
                   offset_drift=0.0)

    @property
    def capacitance_per_area(self) -> float:
        """eps0 eps_r / d_0 [pF/mm^2]."""
        return VACUUM_PERMITTIVITY * self.relative_permittivity / self.dielectric_thickness

    @property
    def adc_step(self) -> float:
        """Converter step [pF] (0 without a converter)."""
        return self.adc_range / 2**self.adc_bits if self.adc_bits else 0.0

    def capacitance_change(self, pressure, pad_area: float) -> np.ndarray:
        """dC [pF] of a pad of ``pad_area`` [mm^2] at mean pressure p [MPa] (steps 2-3; linear: C_0 p / E_d)."""
        return self._elementwise(capacitance_changes, pressure, pad_area)

    def pressure_from_capacitance(self, change, pad_area: float) -> np.ndarray:
        """The firmware's inverse of ``capacitance_change`` [MPa]; beyond the saturated strain it returns the
        pressure at 1 - 1e-9 of it (a saturated node reads its maximum)."""
        return self._elementwise(pressures, change, pad_area)

    def _elementwise(self, kernel, values, pad_area: float) -> np.ndarray:
        values = np.asarray(values, dtype=float)
        out = np.empty(values.size)
        kernel(np.ascontiguousarray(values).ravel(), node_law(self), float(pad_area), out)
        return out.reshape(values.shape) if values.ndim else out[0]

    def realize(self, shape: tuple[int, int], rng) -> "NodeRealization":
        """One built array of ``shape`` (ny, nx) nodes: gains, offsets and drift rates drawn from ``rng`` (a
        Generator or seed) with this node's spreads."""
        rng = np.random.default_rng(rng)
        return NodeRealization(1.0 + self.gain_spread * rng.standard_normal(shape),
                               self.offset_spread * rng.standard_normal(shape),
                               self.offset_drift * rng.standard_normal(shape))

    def read(self, pad_force: np.ndarray, pad_area: float, rng=None, realization: "NodeRealization | None" = None,
             time: float = 0.0) -> np.ndarray:
        """Readings [N] (t, ny, nx) of pads carrying ``pad_force`` [N] (t, ny, nx): steps 2-7 of the module docstring.

        ``rng``: numpy Generator, seed or None, drawn from only when ``noise_floor`` > 0. ``realization``: the built
        array's gains, offsets and drifts (None: every node nominal, no offset), its baseline at ``time`` [s] (of
        every frame) or ``time`` (t,) per frame.
        """
        pad_force = np.asarray(pad_force, dtype=float)
        frames = pad_force.reshape((-1,) + pad_force.shape[-2:])
        shape = frames.shape[1:]
        noise = np.random.default_rng(rng).normal(0.0, self.noise_floor, frames.shape) if self.noise_floor > 0.0 \
            else np.zeros(frames.shape)
        realization = realization or NodeRealization(np.ones(shape), np.zeros(shape), np.zeros(shape))
        times = np.broadcast_to(np.asarray(time, dtype=float), (len(frames),))
        law, change, out = node_law(self), np.empty(shape), np.empty(frames.shape)
        for index, frame in enumerate(frames):
            read_frame(np.ascontiguousarray(frame), float(pad_area), law, realization.gain,
                       realization.offset + times[index] * realization.drift, noise[index], change, out[index])
        return out.reshape(pad_force.shape)

    def force_noise(self) -> float:
        """The noise floor as a pad force [N] at small pressure: noise_floor E_d / c_area (the same for any pad:
        a smaller pad carries less force, dC / dF = c_area / E_d stays)."""
        return self.noise_floor * self.dielectric_modulus / self.capacitance_per_area


@dataclass(frozen=True, eq=False)
class NodeRealization:
    """One built array's nodes (``CapacitiveNode.realize``): gain (ny, nx) [-], baseline offset (ny, nx) [pF] and
    baseline drift rate (ny, nx) [pF/s]."""

    gain: np.ndarray
    offset: np.ndarray
    drift: np.ndarray

    def __post_init__(self):
        shapes = {np.shape(self.gain), np.shape(self.offset), np.shape(self.drift)}
        if len(shapes) != 1 or len(next(iter(shapes))) != 2:
            raise ValueError(f"node realization arrays must share one (ny, nx) shape, got {sorted(shapes)}")
        for name in ("gain", "offset", "drift"):
            value = np.ascontiguousarray(getattr(self, name), dtype=float)
            if not np.all(np.isfinite(value)):
                raise ValueError(f"node realization {name} has non-finite values")
            object.__setattr__(self, name, value)
