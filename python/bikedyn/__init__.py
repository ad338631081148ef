"""bikedyn: bicycle dynamics from symbolic multibody models.

A bicycle (built-in, a parameter file, or a dict such as bicycleparameters'
``Meijaard2007ParameterSet(...).parameters``) is analysed through generated
Rust code of its multibody model: linear stability over forward speed,
parameter sweeps, nonlinear simulation, and the measured-run pipeline
(fit and identify). Results are frozen dataclasses (``Stability``,
``FitResult``, ``Kick`` ..., see :mod:`bikedyn.results`) with NumPy arrays
and complex eigenvalues; names and units are those of the command line's
JSON, in SI units (m, kg, s, rad), and signs the benchmark's (roll and
steer positive to the right) except a simulation's model columns (see
:class:`Simulation`).

Start with::

    import bikedyn
    bike = bikedyn.Bicycle("benchmark")
    print(bike.stability())            # weave and capsize speeds (m/s)
    e = bike.eig(np.linspace(0, 10, 101))
    e.eigenvalues                      # (101, 4) complex, 1/s

``help(bikedyn.Bicycle)`` lists what a bicycle offers; ``bikedyn.models()``
the generated models.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Mapping
from typing import Any, Callable, Dict, Iterable, List, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _bikedyn
from ._errors import (
    ComputationError,
    DataError,
    Error,
    InternalError,
    TooLargeError,
    InvalidArgumentError,
    ModelError,
    NotFoundError,
    OutputError,
    ParameterError,
)
from .results import (
    Bode,
    BodeResponse,
    Canonical,
    CanonicalStandardDeviations,
    ClockOffset,
    CriticalSpeedSensitivity,
    Crossing,
    DiscoveredTerm,
    Discovery,
    EigenvalueDerivative,
    EigenvalueSensitivities,
    Errors,
    Estimate,
    FailedFit,
    FitResult,
    FormFit,
    IdentifyResult,
    Kick,
    ModeSensitivity,
    MonteCarlo,
    Refusal,
    SampledSpeed,
    Sensitivity,
    SpeedDerivative,
    SpeedUncertainty,
    Stability,
    StabilityUncertainty,
    StageErrors,
    VarianceShare,
)

__version__: str = _bikedyn.__version__

__all__ = [
    "Bicycle",
    "Eigen",
    "SweepResult",
    "Simulation",
    "Stability",
    "Crossing",
    "StabilityUncertainty",
    "SpeedUncertainty",
    "VarianceShare",
    "MonteCarlo",
    "SampledSpeed",
    "Canonical",
    "CanonicalStandardDeviations",
    "Sensitivity",
    "CriticalSpeedSensitivity",
    "SpeedDerivative",
    "EigenvalueSensitivities",
    "ModeSensitivity",
    "EigenvalueDerivative",
    "Bode",
    "BodeResponse",
    "FitResult",
    "Kick",
    "FormFit",
    "FailedFit",
    "Refusal",
    "ClockOffset",
    "IdentifyResult",
    "Estimate",
    "Errors",
    "Discovery",
    "DiscoveredTerm",
    "StageErrors",
    "ProgressCallback",
    "sweep",
    "simulate",
    "fit",
    "identify",
    "models",
    "allow_implausible_units",
    "Error",
    "InvalidArgumentError",
    "ParameterError",
    "ModelError",
    "DataError",
    "ComputationError",
    "OutputError",
    "NotFoundError",
    "InternalError",
    "TooLargeError",
]

PathLike = Union[str, "os.PathLike[str]"]


def _doubles(x: Any, name: str) -> Tuple[np.ndarray, bytes]:
    """A 1-D float64 array and its bytes (what the extension reads)."""
    try:
        a = np.ascontiguousarray(np.atleast_1d(np.asarray(x, dtype=np.float64)))
    except (TypeError, ValueError) as e:
        raise InvalidArgumentError(f"{name}: expected numbers ({e})") from None
    if a.ndim != 1:
        raise InvalidArgumentError(f"{name}: expected a 1-D sequence of numbers, got shape {a.shape}")
    return a, a.tobytes()


def _array(buf: bytes, shape: Tuple[int, ...], dtype: Any = np.float64) -> np.ndarray:
    # A writable copy: frombuffer views the immutable bytes.
    return np.frombuffer(buf, dtype=dtype).reshape(shape).copy()


def _nominal_and_std(key: str, value: Any) -> Tuple[float, Optional[float]]:
    """A dict value: a number, or an ``uncertainties`` ufloat (as
    bicycleparameters' ``Bicycle.parameters['Benchmark']`` holds them)."""
    nominal = getattr(value, "nominal_value", None)
    if nominal is not None:
        return float(nominal), float(getattr(value, "std_dev", 0.0))
    try:
        return float(value), None
    except (TypeError, ValueError):
        raise ParameterError(f"parameter `{key}`: {value!r} is not a number") from None


class Eigen(NamedTuple):
    """Eigenvalues and modes over forward speed (``Bicycle.eig``).

    Attributes:
        speeds: forward speeds, shape ``(n,)`` (m/s).
        eigenvalues: shape ``(n, k)`` complex (1/s); columns 0-3 are the
            bicycle's modes in the order of ``modes``, further columns the
            extra states of a model that has them (NaN where absent).
        modes: shape ``(n, 4)`` str: ``weave``, ``capsize``, ``castering``,
            or a merged pair such as ``capsize-castering``.
        eigenvectors: shape ``(n, 4, 4)`` complex: column ``j`` is the mode
            shape of eigenvalue ``j`` over ``[roll, steer, roll rate, steer
            rate]`` (rad, rad/s; benchmark signs), as bicycleparameters
            returns them.
        model: the generated model used.
    """

    speeds: np.ndarray
    eigenvalues: np.ndarray
    modes: np.ndarray
    eigenvectors: np.ndarray
    model: str

    def mode(self, name: str) -> np.ndarray:
        """Eigenvalue of mode ``name`` at each speed (NaN where the mode
        does not exist, e.g. weave below the real-pair merge): for a complex
        pair, the one with positive imaginary part."""
        out = np.full(len(self.speeds), np.nan + 0j)
        for i in range(len(self.speeds)):
            cols = np.nonzero(self.modes[i] == name)[0]
            if cols.size:
                z = self.eigenvalues[i, cols]
                out[i] = z[np.argmax(z.imag)]
        return out


class SweepResult(NamedTuple):
    """Stability over one or two parameters (``bikedyn.sweep``).

    Attributes:
        least_stable_real_part: largest real part of the eigenvalues (1/s;
            negative is stable) at each design and speed, shape
            ``(len(values), len(speeds))`` or ``(len(values),
            len(values2), len(speeds))``.
        weave_speed: weave speed (m/s) of each design within the speeds'
            range (NaN: none), shape ``(len(values),)`` or ``(len(values),
            len(values2))``.
        capsize_speed: capsize speed (m/s), same shape.
        values, values2, speeds: the axes.
        param, param2: the parameter symbols.
        model: the generated model used for every design.
    """

    least_stable_real_part: np.ndarray
    weave_speed: np.ndarray
    capsize_speed: np.ndarray
    values: np.ndarray
    values2: Optional[np.ndarray]
    speeds: np.ndarray
    param: str
    param2: Optional[str]
    model: str


# The generated models' axes are the thesis's (Martin Recuero 2009): roll
# positive leaning right, as the benchmark's, and steer positive turning
# left, minus the benchmark's (runtime/src/linearize/linear_model.rs:
# `steer_sign: -1.0` for every generated model;
# runtime/src/simulate/inputs.rs). The benchmark
# convention (Meijaard et al. 2007) has both positive to the right: the
# signs of `eig`'s eigenvectors, `state_space`, `canonical` and `bode`.
_BENCHMARK_SIGN = {"roll": 1.0, "steer": -1.0}


class Simulation(Dict[str, np.ndarray]):
    """A nonlinear simulation: a dict of arrays with the column names of
    ``bikedyn simulate --out``'s CSV (``t`` in s, coordinates in rad or m,
    their rates with a ``d`` prefix, ``speed`` m/s, energies J, the
    constraint residual m, extra states), in the model's own names and
    signs.

    Two conventions, stated once:

    * The columns (``sim["theta"]``, ``sim["gamma"]``, ``sim["dgamma"]``
      ...) and :meth:`coordinate` are the model's: the generated models use
      the thesis's axes, roll (``theta``) positive leaning right and steer
      (``gamma``) positive turning *left*.
    * :attr:`roll`, :attr:`steer`, :attr:`roll_rate` and :attr:`steer_rate`
      are in the benchmark's signs (Meijaard et al. 2007; bicycleparameters):
      roll positive leaning right, steer positive turning *right*, the signs
      of ``Bicycle.eig``'s eigenvectors, ``state_space``, ``canonical`` and
      ``bode``. So ``sim.roll == sim["theta"]`` and ``sim.steer ==
      -sim["gamma"]``.

    Attributes:
        model: the generated model simulated.
        stop: why the integration stopped (end time, an event).
        stats: the job's summary (``bikedyn::simulate::SimulationSummary``):
            ``model``, ``free_speed``, ``stop``, ``simulated_seconds``,
            ``wall_seconds``, ``rhs_evaluations``, ``accepted_steps``,
            ``rejected_steps``, ``max_constraint_residual`` (m),
            ``max_velocity_residual`` (m/s), ``relative_energy_change``.
        roles: the model's coordinate of each role (``roll``, ``steer``,
            ``yaw``, ``pitch``, ``rear_contact_x`` ...): models name their
            coordinates in their own words (the thesis model's roll is
            ``theta``, its steer ``gamma``, with the thesis's signs).
    """

    model: str
    stop: str
    stats: Dict[str, Any]
    roles: Dict[str, str]

    def coordinate(self, role: str) -> np.ndarray:
        """The time history of the coordinate with ``role`` (``"roll"``,
        ``"steer"`` ...), in the model's units and signs (steer positive
        to the left; :attr:`steer` is the benchmark's)."""
        try:
            return self[self.roles[role]]
        except KeyError:
            raise InvalidArgumentError(f"no coordinate with role {role!r} (roles: {sorted(self.roles)})") from None

    def _benchmark(self, role: str, rate: bool) -> np.ndarray:
        name = self.roles.get(role)
        if name is None:
            raise InvalidArgumentError(f"model {self.model}: no coordinate with role {role!r}")
        return _BENCHMARK_SIGN[role] * self["d" + name if rate else name]

    @property
    def t(self) -> np.ndarray:
        """Time of each sample (s): ``sim["t"]``."""
        return self["t"]

    @property
    def roll(self) -> np.ndarray:
        """Roll angle (rad), benchmark signs: positive leaning right (the
        model's roll column, e.g. ``theta``, which has the same sign)."""
        return self._benchmark("roll", False)

    @property
    def steer(self) -> np.ndarray:
        """Steer angle (rad), benchmark signs: positive turning right (minus
        the model's steer column, e.g. ``-sim["gamma"]``)."""
        return self._benchmark("steer", False)

    @property
    def roll_rate(self) -> np.ndarray:
        """Roll rate (rad/s), benchmark signs (positive rolling right)."""
        return self._benchmark("roll", True)

    @property
    def steer_rate(self) -> np.ndarray:
        """Steer rate (rad/s), benchmark signs (positive turning right;
        ``-sim["dgamma"]``)."""
        return self._benchmark("steer", True)

    def __repr__(self) -> str:
        n = len(self.get("t", ()))
        return f"<Simulation model={self.model!r} samples={n} stop={self.stop!r} columns={list(self)}>"


class Bicycle:
    """A bicycle: its parameters and the generated model that represents it.

    ``Bicycle(spec, name=None, model=None)``:

    * ``spec`` a built-in name (``"benchmark"``: Meijaard et al. 2007,
      Table 1; ``"thesis"``: the instrumented bicycle of the 2009 thesis),
      a parameter file of any form bikedyn reads (TOML in thesis or
      benchmark form, bicycleparameters' ``name = value+/-std`` text), or a
      dict of benchmark or thesis symbols in SI units (m, kg, kg m², rad),
      with any effect parameters (``c_steer`` ...). The parameter dict of
      bicycleparameters' ``Meijaard2007ParameterSet`` is accepted as it is
      (its speed ``v`` is ignored); ``uncertainties`` ufloats keep their
      standard deviation. So is the dict of its
      ``MooreRiderLean2012ParameterSet`` (J. K. Moore's 2012 parameters
      with a leaning rider; without the rider's keys, ``Moore2012ParameterSet``),
      converted to the benchmark form and the ``rider_lean`` model's rider.
    * ``name`` names a dict bicycle in messages.
    * ``model`` a generated model to use for every analysis (default: the
      one that represents the bicycle, see ``bikedyn.models()``).

    Non-physical or malformed parameters raise ``ParameterError`` (a
    ``ValueError``) naming the file or dict, line and field.
    """

    def __init__(self, spec: Union[PathLike, Mapping[str, Any], "Bicycle"], name: Optional[str] = None, model: Optional[str] = None):
        self._spec: Optional[str] = None
        self._b: _bikedyn._Bicycle
        if isinstance(spec, Bicycle):
            self._b = spec._b
            self._spec = spec._spec
        elif isinstance(spec, (str, os.PathLike)):
            s = os.fspath(spec)
            self._b = _bikedyn._Bicycle(s)
            self._spec = s
        elif isinstance(spec, Mapping):
            values = []
            for k, v in spec.items():
                nominal, std = _nominal_and_std(str(k), v)
                values.append((str(k), nominal, std))
            self._b = _bikedyn._Bicycle.from_values(name or "parameter dict", values)
        else:
            raise TypeError(f"Bicycle(spec): expected a name, a path or a dict, got {type(spec).__name__}")
        self._model = model
        if model is not None:
            self._b.model(model)

    @classmethod
    def _wrap(cls, raw: Any, model: Optional[str]) -> "Bicycle":
        b = cls.__new__(cls)
        b._b = raw
        b._spec = None
        b._model = model
        return b

    @property
    def name(self) -> str:
        """The built-in name, file path or dict name."""
        return self._b.name

    @property
    def form(self) -> str:
        """``"benchmark"`` or ``"thesis"``: the form the parameters were given in."""
        return self._b.form

    @property
    def model(self) -> str:
        """The generated model the analyses use."""
        return self._b.model(self._model)

    @property
    def parameters(self) -> Dict[str, float]:
        """Parameters in their form (SI units), then any effect parameters."""
        return dict(self._b.parameters())

    @property
    def uncertainties(self) -> Dict[str, float]:
        """Standard deviations the file or dict gave (``value+/-std``)."""
        return dict(self._b.uncertainties())

    @property
    def warnings(self) -> List[str]:
        """Validation notes (triangle inequality of inertias, extra names)."""
        return list(self._b.warnings())

    def value(self, symbol: str) -> float:
        """Value of any benchmark, thesis or effect symbol (SI units)."""
        v = self._b.value(symbol)
        if v is None:
            raise ParameterError(f"{self.name}: no parameter `{symbol}`")
        return v

    def geometry(self) -> Dict[str, float]:
        """Derived geometry (Meijaard et al. 2007, appendix A): wheelbase
        ``w`` (m), trail ``c`` (m), steer-axis tilt ``lam`` (rad) and
        ``lam_deg`` (deg), total mass ``mT`` (kg) and mass centre ``xT``,
        ``hT`` (m), front assembly mass ``mA`` (kg) and offset ``uA`` (m),
        and the rest of ``bikedyn params show``'s rows."""
        return {s: v for s, v, _unit, _what in self._b.geometry()}

    def geometry_table(self) -> List[Tuple[str, float, str, str]]:
        """``(symbol, value, unit, meaning)`` rows of :meth:`geometry`."""
        return list(self._b.geometry())

    def with_parameter(self, symbol: str, value: float) -> "Bicycle":
        """A copy with one parameter (benchmark, thesis or effect symbol)
        changed, checked as a parameter file's value is (a length over 10 m
        is refused as millimetres)."""
        # `True` is an int to Python; as a mass it would be 1 kg.
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise InvalidArgumentError(f"{self.name}: `{symbol}` = {value!r} is not a number")
        return Bicycle._wrap(self._b.with_parameter(symbol, float(value)), self._model)

    def with_parameters(self, **values: float) -> "Bicycle":
        """A copy with several parameters changed."""
        b = self
        for k, v in values.items():
            b = b.with_parameter(k, v)
        return b

    def to_toml(self) -> str:
        """The parameter file text (TOML), effect parameters included."""
        return self._b.to_toml()

    def canonical(self) -> Canonical:
        """The canonical matrices of ``M q'' + v C1 q' + (g K0 + v² K2) q =
        f`` (Meijaard et al. 2007), ``q = [roll, steer]`` in benchmark
        signs: a :class:`Canonical` with ``M`` (kg m², also ``M0``), ``C1``
        (kg m), ``K0`` (kg m), ``K2`` (kg) as 2x2 arrays, ``model``, ``g``
        (m/s²), and
        ``standard_deviations``: the same four matrices' standard
        deviations that the file's ``+/-`` values imply (first order, exact
        derivatives, parameters independent; what bicycleparameters'
        ``canonical(nominal=False)`` propagates), or ``None`` for a file
        without them. ``ModelError`` when the model's linear equations
        have no such form (damping, a controller, tyre lag)."""
        model, (m0, c1, k0, k2) = self._b.canonical(self._model)
        def r(x: Sequence[float]) -> np.ndarray:
            return np.array(x, dtype=float).reshape(2, 2)

        sd = self._b.canonical_standard_deviations(self._model)
        spread = None if sd is None else CanonicalStandardDeviations(*(r(x) for x in sd))
        return Canonical(r(m0), r(c1), r(k0), r(k2), model, self.value("g"), spread)

    def state_space(self, speeds: Any) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        """``A`` and ``B`` of ``x' = A(v) x + B(v) u`` at each speed (m/s),
        stacked: ``A`` of shape ``(n, k, k)``, ``B`` of shape ``(n, k, 2)``
        with ``x = [roll, steer, roll rate, steer rate]`` (rad, rad/s),
        ``u = [roll torque, steer torque]`` (N m), benchmark signs. For a
        model with extra states (tyre lag) ``k > 4``, the states are those
        of ``state_names(...)`` and ``B`` is ``None``."""
        v, buf = _doubles(speeds, "speeds")
        _model, k, _states, _inputs, a, b = self._b.state_space(buf, self._model)
        A = _array(a, (len(v), k, k))
        B = None if b is None else _array(b, (len(v), k, 2))
        return A, B

    def state_names(self, speed: float = 5.0) -> List[str]:
        """Names of the states of :meth:`state_space`."""
        _v, buf = _doubles([speed], "speed")
        return list(self._b.state_space(buf, self._model)[2])

    def eig(self, speeds: Any) -> Eigen:
        """Eigenvalues (1/s), mode labels and mode shapes at each forward
        speed (m/s); see :class:`Eigen`. One call for any number of speeds
        (no Python loop)."""
        v, buf = _doubles(speeds, "speeds")
        model, k, values, codes, names, vectors = self._b.eig(buf, self._model)
        n = len(v)
        z = _array(values, (n, k, 2))
        eigenvalues = z[..., 0] + 1j * z[..., 1]
        modes = np.array(names if names else ["other"], dtype=object)[_array(codes, (n, 4), np.uint8)]
        w = _array(vectors, (n, 4, 4, 2))
        return Eigen(v.copy(), eigenvalues, modes.astype(str), w[..., 0] + 1j * w[..., 1], model)

    def eigenvalue_standard_deviations(self, speeds: Any) -> Optional[np.ndarray]:
        """Standard deviations of the eigenvalues of :meth:`eig` at
        ``speeds`` (m/s) that the file's ``+/-`` values imply (first order,
        exact derivatives, parameters independent): shape ``(n, 4, 2)``,
        ``[..., 0]`` of the real part and ``[..., 1]`` of the imaginary
        part (1/s), in the order of ``eig(speeds).eigenvalues[:, :4]``; NaN
        at a double eigenvalue (no derivative there). ``None`` for a
        bicycle whose file gives no standard deviations."""
        e = self.eig(speeds)
        z = e.eigenvalues[:, :4]
        pairs = np.stack([z.real, z.imag], axis=-1).ravel().tolist()
        out = self._b.eigenvalue_spread(e.speeds.tolist(), pairs, self._model)
        if out is None:
            return None
        return np.array(out, dtype=float).reshape(len(e.speeds), 4, 2)

    def eigenvalues(self, speeds: Any) -> np.ndarray:
        """Eigenvalues only (1/s), shape ``(n, k)`` complex, each row by
        descending real part: no mode labels or vectors, computed in
        parallel over the speeds (m/s). The fast path for large grids;
        :meth:`eig` labels the modes."""
        v, buf = _doubles(speeds, "speeds")
        _model, k, values = self._b.eigenvalues(buf, self._model)
        z = _array(values, (len(v), k, 2))
        return z[..., 0] + 1j * z[..., 1]

    def stability(
        self,
        speed_max: float = 10.0,
        speed_min: float = 0.0,
        monte_carlo: Optional[int] = None,
        seed: int = 1,
    ) -> Stability:
        """Weave and capsize speeds (m/s) between ``speed_min`` and
        ``speed_max``: a :class:`Stability` with every field of ``bikedyn
        stability --json``: ``weave_speed``, ``capsize_speed``,
        ``weave_real_pair_merge_speed`` (each ``None`` when not in the
        range), ``stable_intervals`` as ``(low, high)`` tuples, every
        :class:`Crossing` with speed, mode, direction and frequency in
        rad/s, ``model``. A file with standard deviations (``value+/-sd``)
        also gives ``weave_speed_sd``, ``capsize_speed_sd`` and
        ``uncertainty`` (first order, from ``speed_min = 0``; see
        ``docs/design-questions.md``), else they are ``None``.
        ``monte_carlo = N`` also draws N bicycles about the file's values
        with its standard deviations (``seed``): ``monte_carlo`` holds each
        speed's drawn ``mean``, ``standard_deviation`` and
        ``standard_error_of_sd`` (m/s), the check of the first order.
        ``to_dict()`` gives the command line's JSON."""
        return Stability._from_json(
            self._b.stability(
                float(speed_min),
                float(speed_max),
                self._model,
                None if monte_carlo is None else int(monte_carlo),
                int(seed),
            )
        )

    def sensitivity(
        self, speed: Optional[float] = None, speed_max: float = 10.0, form: Optional[str] = None
    ) -> Sensitivity:
        """Exact derivatives of the weave and capsize speeds (searched on 0
        to ``speed_max`` m/s) with respect to every parameter, and, with
        ``speed``, of the eigenvalues there: a :class:`Sensitivity` (the
        fields of ``bikedyn sensitivity --format json``): ``weave_speed``
        and ``capsize_speed`` each a :class:`CriticalSpeedSensitivity`
        (``speed``, complex ``eigenvalue``, ``real_part_slope``,
        ``derivatives`` ranked by elasticity) or ``None``; ``eigenvalues``
        (complex derivatives per mode) or ``None``; ``parameter_form``.
        ``form``: ``"benchmark"``, ``"thesis"`` or ``None`` (the bicycle's
        own). A bicycle with an effect raises :class:`ModelError` (exact for
        the canonical form only); see ``docs/design-questions.md``."""
        return Sensitivity._from_json(
            self._b.sensitivity(None if speed is None else float(speed), float(speed_max), form, self._model)
        )

    def bode(self, speed: float, omega_min: float = 0.1, omega_max: float = 100.0, points: int = 200) -> Bode:
        """Frequency response at ``speed`` (m/s): ``G(i omega)`` from the roll
        and steer torques to the roll and steer angles (benchmark signs) on
        ``points`` log-spaced angular frequencies (rad/s). A :class:`Bode`
        (the fields of ``bikedyn bode --format json``): ``omega``, and per
        :class:`BodeResponse` (``input``, ``output``) the complex ``G``,
        ``magnitude_db``, ``phase_deg`` as arrays and ``static_gain``;
        ``.response(input, output)`` picks one, ``.G`` stacks all four as
        ``(n, 2, 2)``."""
        return Bode._from_json(
            self._b.bode(float(speed), float(omega_min), float(omega_max), int(points), self._model)
        )

    def _as_spec(self, stack: List[Any]) -> str:
        """A spec the pipelines resolve: the original name or file, or a
        temporary TOML file of a dict or modified bicycle."""
        if self._spec is not None:
            return self._spec
        d = tempfile.TemporaryDirectory(prefix="bikedyn-")
        stack.append(d)
        path = os.path.join(d.name, "bicycle.toml")
        with open(path, "w", encoding="utf-8") as f:
            f.write(self.to_toml())
        return path

    def __repr__(self) -> str:
        return f"Bicycle({self.name!r}, form={self.form!r}, model={self.model!r})"


BikeLike = Union[Bicycle, PathLike, Mapping[str, Any]]


def _bicycle(bike: BikeLike) -> Bicycle:
    return bike if isinstance(bike, Bicycle) else Bicycle(bike)


def sweep(
    bike: BikeLike,
    param: str,
    values: Any,
    speeds: Any,
    param2: Optional[str] = None,
    values2: Any = None,
    model: Optional[str] = None,
) -> SweepResult:
    """Stability of every design over ``values`` of parameter ``param``
    (and ``values2`` of ``param2``: a map) at every forward speed in
    ``speeds`` (m/s): least-stable real part per design and speed, weave and
    capsize speeds per design (within the speeds' range). Designs run in
    parallel on every core, without the GIL. A design that cannot be
    analysed raises with the parameter values in the message. See
    :class:`SweepResult`."""
    b = _bicycle(bike)
    x, xb = _doubles(values, "values")
    v, vb = _doubles(speeds, "speeds")
    y, yb = (None, None) if values2 is None else _doubles(values2, "values2")
    if (param2 is None) != (values2 is None):
        raise InvalidArgumentError("param2 and values2 go together")
    used, least, weave, capsize = _bikedyn.sweep(b._b, param, xb, vb, param2, yb, model or b._model)
    shape = (len(x),) if y is None else (len(x), len(y))
    return SweepResult(
        _array(least, shape + (len(v),)),
        _array(weave, shape),
        _array(capsize, shape),
        x.copy(),
        None if y is None else y.copy(),
        v.copy(),
        param,
        param2,
        used,
    )


def simulate(
    bike: BikeLike,
    duration: float = 5.0,
    speed: float = 5.0,
    roll: float = 0.0,
    steer: float = 0.0,
    roll_rate: float = 0.0,
    steer_rate: float = 0.0,
    yaw: float = 0.0,
    kicks: Iterable[Sequence[float]] = (),
    pulses: Iterable[Sequence[Any]] = (),
    model: Optional[str] = None,
    free_speed: bool = False,
    rtol: float = 1e-8,
    atol: float = 1e-10,
    method: str = "dop853",
    dt: float = 0.01,
    roll_limit: Optional[float] = None,
    steer_limit: Optional[float] = None,
) -> Simulation:
    """Nonlinear simulation from upright straight running, perturbed.

    Initial ``roll``, ``steer`` (rad), ``roll_rate``, ``steer_rate``
    (rad/s), ``speed`` (m/s), ``yaw`` (rad), in the model's signs as the
    command line's ``--roll`` and ``--steer``: roll positive leaning right,
    steer positive turning *left* (the thesis's axes; the benchmark's steer
    is minus this). ``kicks``: ``(time s,
    impulse N s)`` or ``(time, impulse, ahead m, height m)`` lateral
    impulses on the rear frame; ``pulses``: ``(target, start s, duration
    s, amplitude N m[, shape])`` with target ``"roll"`` or ``"steer"``
    (the torque in the model's signs, as the angles),
    shape ``"rect"`` (default) or ``"halfsine"``. ``free_speed``: the speed
    is a state (the model's free-speed variant), else it is held.
    ``roll_limit``, ``steer_limit`` (rad) stop the run when exceeded.
    Returns a :class:`Simulation`: a dict of arrays with the CSV's column
    names (the model's signs), and ``sim.roll``, ``sim.steer``,
    ``sim.roll_rate``, ``sim.steer_rate`` in the benchmark's signs (both
    positive to the right, as ``Bicycle.eig``'s eigenvectors)."""
    b = _bicycle(bike)
    ks: List[Tuple[float, float, Optional[float], Optional[float]]] = []
    for kick in kicks:
        k = tuple(float(x) for x in kick)
        if len(k) == 2:
            ks.append((k[0], k[1], None, None))
        elif len(k) == 4:
            ks.append((k[0], k[1], k[2], k[3]))
        else:
            raise InvalidArgumentError(f"kick {k}: expected (time, impulse) or (time, impulse, ahead, height)")
    ps = []
    for p in pulses:
        p = tuple(p)
        if len(p) not in (4, 5):
            raise InvalidArgumentError(f"pulse {p}: expected (target, start, duration, amplitude[, shape])")
        ps.append((str(p[0]), float(p[1]), float(p[2]), float(p[3]), str(p[4]) if len(p) == 5 else "rect"))
    initial = (float(roll), float(steer), float(roll_rate), float(steer_rate), float(speed), float(yaw))
    model_used, header, columns, samples, stop, stats, roles = _bikedyn.simulate(
        b._b, float(duration), initial, ks, ps, model or b._model, bool(free_speed),
        float(rtol), float(atol), str(method), float(dt),
        None if roll_limit is None else float(roll_limit),
        None if steer_limit is None else float(steer_limit),
    )
    data = _array(columns, (len(header), samples))
    out = Simulation(zip(header, data))
    out.model = model_used
    out.stop = stop
    out.stats = json.loads(stats)
    out.roles = dict(roles)
    return out


def _paths(paths: Union[PathLike, Iterable[PathLike]], what: str) -> List[str]:
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    out = [os.fspath(p) for p in paths]
    if not out:
        raise InvalidArgumentError(f"{what}: no paths given")
    for p in out:
        if not os.path.exists(p):
            raise NotFoundError(f"{p}: no such run folder, set folder or log")
    return out


ProgressCallback = Callable[[str, int, Optional[int]], None]
"""A progress callback of :func:`fit` and :func:`identify`:
``progress(step, done, total)`` with ``step`` what was just done in words
(``"runs"``, ``"fitted steer_damping"``, ``"score test of 30 candidates"``),
``done`` the steps of that stage done so far and ``total`` their number when
known in advance, else ``None``. It is called from the computation's worker
threads (one call at a time); an exception it raises stops the reports and
is raised when the computation has finished."""


def fit(
    paths: Union[PathLike, Iterable[PathLike]],
    calibration: Optional[PathLike] = None,
    bike: Optional[BikeLike] = None,
    angles: str = "direct",
    nominal_clock: bool = False,
    progress: Optional[ProgressCallback] = None,
) -> FitResult:
    """Measured weave eigenvalues from raw runs (``bikedyn fit``): run
    folders, set folders or TU Delft logs. ``calibration``: the calibration
    run (default: ``calibration/`` beside the runs). ``bike``: the bicycle whose
    model predicts each kick's weave and judges the fitted eigenvalues
    (default: the built-in thesis bicycle for thesis-format runs; TU Delft
    logs need theirs). ``progress``: called as
    ``progress(step, done, total)`` after each run or log (see
    :data:`ProgressCallback`). Returns a :class:`FitResult`: ``kicks``,
    each a :class:`Kick` with the fitted weave eigenvalue as a complex
    (1/s), its standard errors, r² and the model's prediction."""
    stack: List[Any] = []
    spec = None if bike is None else _bicycle(bike)._as_spec(stack)
    cal = None if calibration is None else _paths(calibration, "calibration")[0]
    return FitResult._from_raw(_bikedyn.fit(_paths(paths, "fit"), cal, spec, angles, nominal_clock, progress))


def _count(name: str, value: Any, low: int, high: int) -> int:
    """An integer argument within ``[low, high]``, or an
    :class:`InvalidArgumentError` naming it."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        raise InvalidArgumentError(f"{name} = {value!r}: must be an integer from {low} to {high}")
    return int(value)


def identify(
    paths_or_eigen_table: Union[PathLike, Iterable[PathLike]],
    bike: Optional[BikeLike] = None,
    effects: Sequence[str] = (),
    folds: int = 4,
    corrections: Optional[int] = None,
    calibration: Optional[PathLike] = None,
    progress: Optional[ProgressCallback] = None,
    discover: bool = True,
    max_fits_per_step: Optional[int] = None,
    family_wise_bar: bool = False,
) -> IdentifyResult:
    """Close the loop (``bikedyn identify``): fit the base model to measured
    runs, diagnose the residual, select effects and parameter corrections
    (information criterion and cross-validation by run) and report the
    error before and after. Given one ``.csv`` file, the measured
    eigenvalue table form (``identify --eigenvalues``: speed, real part,
    imaginary part, optional standard errors). ``bike``: the bicycle
    (default: the built-in thesis bicycle for thesis-format runs; TU Delft
    logs and a table need theirs). ``effects``: the candidate
    effects' symbols (default: all); ``corrections``: at most this many
    parameter corrections (0: effects only). ``progress``: called as
    ``progress(step, done, total)`` after each step of the selection (see
    :data:`ProgressCallback`; the eigenvalue table form takes seconds and
    does not report). ``discover``: after the library, search a dictionary
    of generalized forces on the roll and steer equations, on the table or
    on the kicks' weave eigenvalues (``result.discovery``; the command
    line's ``--no-discover`` is ``discover=False``).
    ``max_fits_per_step``: at most this many candidate fits per step of
    the library's search beyond its contenders (a compute budget for large
    sets of runs; default: none, a step that adds nothing has fitted every
    candidate predicted to gain). ``family_wise_bar``: raise each step's
    bar of a consistent held-out gain with the candidates it has fitted (a
    Bonferroni bar; the command line's ``--family-wise-bar``; default: two
    standard errors for each). Returns an
    :class:`IdentifyResult`: ``selected``, ``parameters`` (each an
    :class:`Estimate` with its 95 % interval), ``error_before`` and
    ``error_after`` (fitted and held out), ``discovery``; ``summary()``,
    ``write_report(dir)`` and ``to_dict()`` (the full JSON)."""
    # As the command line's --folds and --corrections: named, with their range
    # (an int beyond the machine's would be an OverflowError naming nothing).
    folds = _count("folds", folds, 2, 1000)
    corrections = None if corrections is None else _count("corrections", corrections, 0, 1_000_000)
    max_fits_per_step = (
        None if max_fits_per_step is None else _count("max_fits_per_step", max_fits_per_step, 1, 1_000_000)
    )
    stack: List[Any] = []
    spec = None if bike is None else _bicycle(bike)._as_spec(stack)
    if isinstance(paths_or_eigen_table, (str, os.PathLike)) and os.fspath(paths_or_eigen_table).lower().endswith(".csv"):
        if max_fits_per_step is not None:
            raise InvalidArgumentError("max_fits_per_step applies to runs and logs, not to an eigenvalue table")
        if family_wise_bar:
            raise InvalidArgumentError("family_wise_bar applies to runs and logs, not to an eigenvalue table")
        table = _paths(paths_or_eigen_table, "identify")[0]
        return IdentifyResult._from_json(
            _bikedyn.identify_eigenvalues(table, spec, list(effects), corrections, bool(discover))
        )
    cal = None if calibration is None else _paths(calibration, "calibration")[0]
    return IdentifyResult._from_json(
        _bikedyn.identify(
            _paths(paths_or_eigen_table, "identify"),
            cal,
            spec,
            list(effects),
            folds,
            corrections,
            progress,
            bool(discover),
            max_fits_per_step,
            bool(family_wise_bar),
        )
    )


def models() -> List[Dict[str, Any]]:
    """The generated models (``bikedyn models --json``): name, base model,
    effects, coordinates and parameters with units."""
    out: List[Dict[str, Any]] = json.loads(_bikedyn.models())
    return out


def allow_implausible_units(allow: bool = True) -> None:
    """Accept parameter files whose lengths look like millimetres (the
    command line's ``--allow-units``) for the rest of this process."""
    _bikedyn.allow_implausible_units(bool(allow))
