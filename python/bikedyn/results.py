"""Typed results of bikedyn's analyses: frozen dataclasses built from the
JSON the extension returns (the command line's ``--json``), with NumPy
arrays for sampled quantities and Python ``complex`` for eigenvalues.

Every class is importable from :mod:`bikedyn`. A result that comes from the
command line's JSON keeps that JSON: ``to_dict()`` gives it as the command
line prints it, so no field of the command line is lost even where the
dataclass leaves a nested detail out.

Units are SI throughout (m, kg, s, rad); eigenvalues are in 1/s (their
imaginary parts in rad/s); signs are the benchmark's (Meijaard et al.
2007: roll positive to the right, steer positive to the right) unless a
field says otherwise.
"""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass
from typing import Any, Dict, Mapping, Optional, Tuple, TypeVar, Union

import numpy as np

__all__ = [
    "Crossing",
    "VarianceShare",
    "SpeedUncertainty",
    "StabilityUncertainty",
    "SampledSpeed",
    "MonteCarlo",
    "Stability",
    "Canonical",
    "CanonicalStandardDeviations",
    "SpeedDerivative",
    "CriticalSpeedSensitivity",
    "EigenvalueDerivative",
    "ModeSensitivity",
    "EigenvalueSensitivities",
    "Sensitivity",
    "BodeResponse",
    "Bode",
    "FormFit",
    "FailedFit",
    "Refusal",
    "ClockOffset",
    "Kick",
    "FitResult",
    "Estimate",
    "Errors",
    "StageErrors",
    "DiscoveredTerm",
    "Discovery",
    "IdentifyResult",
]

PathLike = Union[str, "os.PathLike[str]"]

# What the extension's parameter intervals are: value +- 1.96 standard
# errors (src/identify/result.rs, `Estimate`: `low`, `high`).
CONFIDENCE = 0.95


def _complex(pair: Any) -> Optional[complex]:
    """``[re, im]`` of the JSON as a Python complex (``None`` stays)."""
    if pair is None:
        return None
    re, im = pair
    return complex(_float(re), _float(im))


def _float(x: Any) -> float:
    """A JSON number (serde writes NaN as ``null``)."""
    return float("nan") if x is None else float(x)


def _opt_float(x: Any) -> Optional[float]:
    return None if x is None else float(x)


def _pair(x: Any) -> Optional[Tuple[float, float]]:
    if x is None:
        return None
    a, b = x
    return (_float(a), _float(b))


_T = TypeVar("_T")


def _attach(obj: _T, **hidden: Any) -> _T:
    """Keep what is not a field (the JSON, the extension's object) on a
    frozen dataclass, out of its fields, ``repr`` and comparison."""
    for k, v in hidden.items():
        object.__setattr__(obj, k, v)
    return obj


class _Subscript:
    """``result["field"]``: the dict access of the results that were dicts
    before they were dataclasses (bikedyn 0.1), deprecated; use
    ``result.field``. Values are the dataclass's (tuples, complex numbers,
    dataclasses), not the JSON's."""

    def __getitem__(self, key: str) -> Any:
        if not isinstance(key, str):
            raise TypeError(f"{type(self).__name__} indices are field names")
        warnings.warn(
            f"{type(self).__name__}[{key!r}] is deprecated: the result is a dataclass, use .{key}",
            DeprecationWarning,
            stacklevel=2,
        )
        try:
            return getattr(self, key)
        except AttributeError:
            raise KeyError(key) from None


class _FromJson:
    """``to_dict()``: the command line's JSON that a result was built from."""

    _json: str

    def to_dict(self) -> Dict[str, Any]:
        """The result as the command line's JSON prints it (a new dict)."""
        d: Dict[str, Any] = json.loads(self._json)
        return d


# --------------------------------------------------------------------------
# stability


@dataclass(frozen=True)
class Crossing(_Subscript):
    """One speed where a real part of an eigenvalue crosses zero.

    Attributes:
        speed: forward speed of the crossing (m/s).
        mode: the mode crossing: ``weave``, ``capsize``, ``castering`` or a
            merged pair's name.
        direction: ``"stabilizing"`` or ``"destabilizing"``, with
            increasing speed.
        kind: ``"complex_pair"`` or ``"real_root"``.
        frequency: imaginary part of the eigenvalue at the crossing (rad/s;
            0 for a real root).
    """

    speed: float
    mode: str
    direction: str
    kind: str
    frequency: float

    @classmethod
    def _of(cls, d: Mapping[str, Any]) -> "Crossing":
        return cls(_float(d["speed"]), d["mode"], d["direction"], d["kind"], _float(d["frequency"]))


@dataclass(frozen=True)
class VarianceShare(_Subscript):
    """One parameter's part in a critical speed's variance.

    Attributes:
        parameter: the parameter symbol (the file's own form).
        standard_deviation: its standard deviation as the file gives it
            (the parameter's unit, SI).
        share: ``(dv/dp sd_p)^2`` over the speed's variance (fraction, 0 to 1).
    """

    parameter: str
    standard_deviation: float
    share: float


@dataclass(frozen=True)
class SpeedUncertainty(_Subscript):
    """A critical speed's standard deviation from the file's ``+/-`` values
    (first order, exact derivatives, parameters independent).

    Attributes:
        speed: the critical speed (m/s).
        standard_deviation: its standard deviation (m/s),
            ``sqrt(sum (dv/dp sd_p)^2)``.
        shares: each parameter's share of the variance, largest first.
    """

    speed: float
    standard_deviation: float
    shares: Tuple[VarianceShare, ...]

    @classmethod
    def _of(cls, d: Optional[Mapping[str, Any]]) -> Optional["SpeedUncertainty"]:
        if d is None:
            return None
        shares = tuple(
            VarianceShare(s["parameter"], _float(s["standard_deviation"]), _float(s["share"])) for s in d["shares"]
        )
        return cls(_float(d["speed"]), _float(d["standard_deviation"]), shares)


@dataclass(frozen=True)
class StabilityUncertainty(_Subscript):
    """The first-order propagation of the file's standard deviations to the
    weave and capsize speeds.

    Attributes:
        weave_speed: the weave speed's, or ``None`` (no weave speed in range).
        capsize_speed: the capsize speed's, or ``None``.
    """

    weave_speed: Optional[SpeedUncertainty]
    capsize_speed: Optional[SpeedUncertainty]


@dataclass(frozen=True)
class SampledSpeed(_Subscript):
    """One critical speed over the Monte Carlo draws that have it.

    Attributes:
        mean: mean over the draws (m/s).
        standard_deviation: sample standard deviation (m/s).
        standard_error_of_sd: standard error of that standard deviation
            (m/s), ``sd / sqrt(2 (n - 1))``.
        draws: number of draws with the speed in the searched range.
    """

    mean: float
    standard_deviation: float
    standard_error_of_sd: float
    draws: int

    @classmethod
    def _of(cls, d: Optional[Mapping[str, Any]]) -> Optional["SampledSpeed"]:
        if d is None:
            return None
        return cls(_float(d["mean"]), _float(d["standard_deviation"]), _float(d["standard_error_of_sd"]), int(d["draws"]))


@dataclass(frozen=True)
class MonteCarlo(_Subscript):
    """The critical speeds of bicycles drawn about the file's values with
    its standard deviations (``stability(monte_carlo=N)``).

    Attributes:
        draws: bicycles drawn.
        seed: their seed.
        not_a_bicycle: draws whose parameters are no bicycle (a negative
            mass ...), left out.
        weave_speed: the drawn weave speeds, or ``None`` (no draw has one).
        capsize_speed: the drawn capsize speeds, or ``None``.
    """

    draws: int
    seed: int
    not_a_bicycle: int
    weave_speed: Optional[SampledSpeed]
    capsize_speed: Optional[SampledSpeed]


@dataclass(frozen=True)
class Stability(_FromJson, _Subscript):
    """Weave and capsize speeds of a bicycle (``Bicycle.stability``, the
    JSON of ``bikedyn stability --json``).

    Attributes:
        bike: the bicycle as named (built-in name, file or dict name).
        model: the generated model analysed.
        weave_speed: ``v_w``, where the weave becomes stable (m/s); ``None``
            when not in the searched range.
        capsize_speed: ``v_c``, where the capsize mode becomes unstable
            (m/s); ``None`` when not in range.
        weave_real_pair_merge_speed: ``v_d``, where two real roots merge
            into the weave pair (m/s); ``None`` when not in range.
        stable_intervals: maximal speed intervals ``(low, high)`` (m/s)
            where every real part is negative.
        crossings: every zero crossing of a real part in the range,
            ascending in speed.
        weave_speed_sd: standard deviation of ``weave_speed`` (m/s) from the
            file's ``+/-`` values (first order); ``None`` without them.
        capsize_speed_sd: standard deviation of ``capsize_speed`` (m/s);
            ``None`` without ``+/-`` values.
        uncertainty: the first-order propagation in full (each parameter's
            share of the variance); ``None`` without ``+/-`` values.
        monte_carlo: the Monte Carlo check (``monte_carlo=N``); ``None``
            when not asked for.

    ``to_dict()`` gives the command line's JSON.
    """

    bike: str
    model: str
    weave_speed: Optional[float]
    capsize_speed: Optional[float]
    weave_real_pair_merge_speed: Optional[float]
    stable_intervals: Tuple[Tuple[float, float], ...]
    crossings: Tuple[Crossing, ...]
    weave_speed_sd: Optional[float] = None
    capsize_speed_sd: Optional[float] = None
    uncertainty: Optional[StabilityUncertainty] = None
    monte_carlo: Optional[MonteCarlo] = None

    @classmethod
    def _from_json(cls, text: str) -> "Stability":
        d = json.loads(text)
        u = d.get("uncertainty")
        m = d.get("monte_carlo")
        out = cls(
            bike=d["bike"],
            model=d["model"],
            weave_speed=_opt_float(d["weave_speed"]),
            capsize_speed=_opt_float(d["capsize_speed"]),
            weave_real_pair_merge_speed=_opt_float(d["weave_real_pair_merge_speed"]),
            stable_intervals=tuple((_float(lo), _float(hi)) for lo, hi in d["stable_intervals"]),
            crossings=tuple(Crossing._of(c) for c in d["crossings"]),
            weave_speed_sd=_opt_float(d.get("weave_speed_sd")),
            capsize_speed_sd=_opt_float(d.get("capsize_speed_sd")),
            uncertainty=None
            if u is None
            else StabilityUncertainty(SpeedUncertainty._of(u["weave_speed"]), SpeedUncertainty._of(u["capsize_speed"])),
            monte_carlo=None
            if m is None
            else MonteCarlo(
                int(m["draws"]),
                int(m["seed"]),
                int(m["not_a_bicycle"]),
                SampledSpeed._of(m["weave_speed"]),
                SampledSpeed._of(m["capsize_speed"]),
            ),
        )
        return _attach(out, _json=text)

    def is_stable_at(self, speed: float) -> bool:
        """Whether ``speed`` (m/s) lies in one of the stable intervals."""
        return any(lo <= speed <= hi for lo, hi in self.stable_intervals)


# --------------------------------------------------------------------------
# canonical matrices


@dataclass(frozen=True, eq=False)
class CanonicalStandardDeviations(_Subscript):
    """Standard deviations of the canonical matrices' entries that the
    file's ``+/-`` values imply (first order, exact derivatives, parameters
    independent; bicycleparameters' ``canonical(nominal=False)``).

    Attributes:
        M: of the mass matrix, 2x2 (kg m²).
        C1: of the damping-like matrix, 2x2 (kg m).
        K0: of the gravity stiffness matrix, 2x2 (kg m).
        K2: of the speed stiffness matrix, 2x2 (kg).
    """

    M: np.ndarray
    C1: np.ndarray
    K0: np.ndarray
    K2: np.ndarray

    @property
    def M0(self) -> np.ndarray:
        """``M`` under its older name (kg m²)."""
        return self.M


@dataclass(frozen=True, eq=False)
class Canonical(_Subscript):
    """The canonical matrices of ``M q'' + v C1 q' + (g K0 + v² K2) q = f``
    (Meijaard et al. 2007), ``q = [roll, steer]`` (rad), ``f = [roll
    torque, steer torque]`` (N m), benchmark signs (``Bicycle.canonical``).

    Attributes:
        M: mass matrix, 2x2 (kg m²); also ``M0``.
        C1: damping-like matrix per speed, 2x2 (kg m).
        K0: gravity stiffness matrix per g, 2x2 (kg m).
        K2: stiffness matrix per speed squared, 2x2 (kg).
        model: the generated model whose linearization they are.
        g: the bicycle's gravitational acceleration (m/s²), the ``g`` of
            ``g K0``.
        standard_deviations: the entries' standard deviations from the
            file's ``+/-`` values (first order), or ``None`` for a bicycle
            without them.
    """

    M: np.ndarray
    C1: np.ndarray
    K0: np.ndarray
    K2: np.ndarray
    model: str
    g: float
    standard_deviations: Optional[CanonicalStandardDeviations]

    @property
    def M0(self) -> np.ndarray:
        """``M`` under its older name (kg m²)."""
        return self.M

    def stiffness(self, speed: float) -> np.ndarray:
        """``g K0 + v² K2`` at forward speed ``speed`` (m/s), 2x2 (N m/rad)."""
        return self.g * self.K0 + speed**2 * self.K2

    def damping(self, speed: float) -> np.ndarray:
        """``v C1`` at forward speed ``speed`` (m/s), 2x2 (N m s/rad)."""
        return speed * self.C1


# --------------------------------------------------------------------------
# sensitivity


@dataclass(frozen=True)
class SpeedDerivative(_Subscript):
    """One parameter's derivative of a critical speed.

    Attributes:
        parameter: the parameter symbol (benchmark or thesis form).
        value: its value (SI).
        derivative: ``dv*/dp`` (m/s per unit of the parameter).
        elasticity: ``(p / v*) dv*/dp``: per cent of speed per per cent of
            the parameter (dimensionless).
    """

    parameter: str
    value: float
    derivative: float
    elasticity: float


@dataclass(frozen=True)
class CriticalSpeedSensitivity(_Subscript):
    """The sensitivity of one critical speed to every parameter.

    Attributes:
        speed: the critical speed (m/s).
        eigenvalue: the eigenvalue crossing there (1/s; real part 0 up to
            rounding).
        real_part_slope: ``d Re s / dv`` at the crossing (1/s per m/s).
        derivatives: one per parameter, ranked by the size of the
            elasticity (largest first).
    """

    speed: float
    eigenvalue: complex
    real_part_slope: float
    derivatives: Tuple[SpeedDerivative, ...]

    @classmethod
    def _of(cls, d: Optional[Mapping[str, Any]]) -> Optional["CriticalSpeedSensitivity"]:
        if d is None:
            return None
        ds = tuple(
            SpeedDerivative(x["parameter"], _float(x["value"]), _float(x["derivative"]), _float(x["elasticity"]))
            for x in d["derivatives"]
        )
        return cls(_float(d["speed"]), _complex(d["eigenvalue"]), _float(d["real_part_slope"]), ds)  # type: ignore[arg-type]

    def derivative(self, parameter: str) -> SpeedDerivative:
        """The derivative with respect to ``parameter``."""
        for d in self.derivatives:
            if d.parameter == parameter:
                return d
        raise KeyError(parameter)


@dataclass(frozen=True)
class EigenvalueDerivative(_Subscript):
    """One parameter's derivative of an eigenvalue.

    Attributes:
        parameter: the parameter symbol (benchmark or thesis form).
        value: its value (SI).
        derivative: ``ds/dp`` (1/s per unit of the parameter).
        scaled: ``p ds/dp`` (1/s): the change for a 100 % change of the
            parameter, to first order; comparable across parameters.
    """

    parameter: str
    value: float
    derivative: complex
    scaled: complex


@dataclass(frozen=True)
class ModeSensitivity(_Subscript):
    """The derivatives of one eigenvalue at a speed.

    Attributes:
        mode: the mode (``weave``, ``capsize``, ``castering``, a merged pair).
        eigenvalue: the eigenvalue (1/s); of a pair, the root with positive
            imaginary part.
        speed_derivative: ``ds/dv`` (1/s per m/s).
        derivatives: one per parameter, ranked by ``|p ds/dp|`` (largest
            first).
    """

    mode: str
    eigenvalue: complex
    speed_derivative: complex
    derivatives: Tuple[EigenvalueDerivative, ...]


@dataclass(frozen=True)
class EigenvalueSensitivities(_Subscript):
    """The eigenvalues' derivatives at one speed.

    Attributes:
        speed: forward speed (m/s).
        modes: one per real eigenvalue and per complex pair, in mode order.
    """

    speed: float
    modes: Tuple[ModeSensitivity, ...]


@dataclass(frozen=True)
class Sensitivity(_FromJson, _Subscript):
    """Exact derivatives of the critical speeds (and the eigenvalues at a
    speed) with respect to every parameter (``Bicycle.sensitivity``, the
    JSON of ``bikedyn sensitivity --format json``).

    Attributes:
        bike: the bicycle as named.
        model: the generated model of the matrices.
        parameter_form: ``"benchmark"`` or ``"thesis"``: the parameters
            differentiated with respect to (SI units).
        speed_max: upper end of the searched speeds (m/s).
        weave_speed: the weave speed's sensitivity, or ``None`` (no weave
            crossing in range).
        capsize_speed: the capsize speed's, or ``None``.
        eigenvalues: the eigenvalues' at the speed asked for, or ``None``.
        closed_form_departure: largest relative difference between the
            closed-form canonical matrices and the generated model's
            (dimensionless).
    """

    bike: str
    model: str
    parameter_form: str
    speed_max: float
    weave_speed: Optional[CriticalSpeedSensitivity]
    capsize_speed: Optional[CriticalSpeedSensitivity]
    eigenvalues: Optional[EigenvalueSensitivities]
    closed_form_departure: float

    @classmethod
    def _from_json(cls, text: str) -> "Sensitivity":
        d = json.loads(text)
        e = d.get("eigenvalues")
        eig = None
        if e is not None:
            modes = tuple(
                ModeSensitivity(
                    m["mode"],
                    _complex(m["eigenvalue"]),  # type: ignore[arg-type]
                    _complex(m["speed_derivative"]),  # type: ignore[arg-type]
                    tuple(
                        EigenvalueDerivative(
                            x["parameter"], _float(x["value"]), _complex(x["derivative"]), _complex(x["scaled"])  # type: ignore[arg-type]
                        )
                        for x in m["derivatives"]
                    ),
                )
                for m in e["modes"]
            )
            eig = EigenvalueSensitivities(_float(e["speed"]), modes)
        out = cls(
            bike=d["bike"],
            model=d["model"],
            parameter_form=d["parameter_form"],
            speed_max=_float(d["speed_max"]),
            weave_speed=CriticalSpeedSensitivity._of(d.get("weave_speed")),
            capsize_speed=CriticalSpeedSensitivity._of(d.get("capsize_speed")),
            eigenvalues=eig,
            closed_form_departure=_float(d["closed_form_departure"]),
        )
        return _attach(out, _json=text)


# --------------------------------------------------------------------------
# frequency response


@dataclass(frozen=True, eq=False)
class BodeResponse(_Subscript):
    """The frequency response of one input-output pair.

    Attributes:
        input: ``"roll_torque"`` or ``"steer_torque"``.
        output: ``"roll"`` or ``"steer"``.
        G: ``G(i omega)`` at each frequency, complex array (rad/(N m)),
            benchmark signs.
        magnitude_db: ``20 log10 |G|`` (dB re 1 rad/(N m)).
        phase_deg: phase of ``G`` (degrees), unwrapped along the
            frequencies from its principal value at the first.
        static_gain: ``G(0) = -C A^-1 B`` (rad/(N m)); ``None`` at a zero
            eigenvalue.
    """

    input: str
    output: str
    G: np.ndarray
    magnitude_db: np.ndarray
    phase_deg: np.ndarray
    static_gain: Optional[float]


@dataclass(frozen=True, eq=False)
class Bode(_FromJson, _Subscript):
    """Frequency response at one speed (``Bicycle.bode``, the JSON of
    ``bikedyn bode --format json``), from the roll and steer torques to the
    roll and steer angles.

    Attributes:
        bike: the bicycle as named.
        model: the generated model of the equations.
        units: the units in words, as the command line states them.
        speed: forward speed (m/s).
        stable: whether every eigenvalue has a negative real part there.
        omega: angular frequencies, shape ``(n,)`` (rad/s).
        responses: one per input-output pair: roll torque to roll, to
            steer, steer torque to roll, to steer.
    """

    bike: str
    model: str
    units: str
    speed: float
    stable: bool
    omega: np.ndarray
    responses: Tuple[BodeResponse, ...]

    @classmethod
    def _from_json(cls, text: str) -> "Bode":
        d = json.loads(text)

        def arr(x: Any) -> np.ndarray:
            return np.array([_float(v) for v in x], dtype=float)

        responses = tuple(
            BodeResponse(
                g["input"],
                g["output"],
                arr(g["re"]) + 1j * arr(g["im"]),
                arr(g["magnitude_db"]),
                arr(g["phase_deg"]),
                _opt_float(g["static_gain"]),
            )
            for g in d["responses"]
        )
        out = cls(d["bike"], d["model"], d["units"], _float(d["speed"]), bool(d["stable"]), arr(d["omega"]), responses)
        return _attach(out, _json=text)

    def response(self, input: str, output: str) -> BodeResponse:
        """The response from ``input`` (``"roll_torque"``,
        ``"steer_torque"``) to ``output`` (``"roll"``, ``"steer"``)."""
        for r in self.responses:
            if r.input == input and r.output == output:
                return r
        raise KeyError(f"no response from {input!r} to {output!r}")

    @property
    def G(self) -> np.ndarray:
        """All four responses as one complex array of shape ``(n, 2, 2)``:
        ``G[k, i, j]`` from input ``j`` (roll torque, steer torque) to
        output ``i`` (roll, steer) at ``omega[k]`` (rad/(N m))."""
        out = np.full((len(self.omega), 2, 2), np.nan + 0j)
        outputs, inputs = ("roll", "steer"), ("roll_torque", "steer_torque")
        for r in self.responses:
            out[:, outputs.index(r.output), inputs.index(r.input)] = r.G
        return out


# --------------------------------------------------------------------------
# fit


@dataclass(frozen=True)
class FormFit:
    """One fitted form of a kick's free response.

    Attributes:
        form: the fitted form's name (``eq94_roll_angle``,
            ``kooijman_roll_rate``, ``speed_varying_roll_angle`` ...).
        eigenvalue: the fitted eigenvalue (1/s).
        stderr: standard errors of its real and imaginary parts ``(re, im)``
            (1/s).
        r2: coefficient of determination of the fit.
        rms: RMS residual of the fit (the signal's unit: rad or rad/s);
            ``None`` where not reported (a refused kick's chosen fit).
        aic: Akaike information criterion; ``None`` where not reported.
        bic: Bayesian information criterion; ``None`` where not reported.
        n: samples fitted; ``None`` where not reported.
        slope_per_mps: of a speed-varying form, the eigenvalue's slope with
            speed ((1/s) per m/s); else ``None``.
        slope_stderr: standard errors of the slope's real and imaginary
            parts ``(re, im)``; else ``None``.
    """

    form: str
    eigenvalue: complex
    stderr: Tuple[float, float]
    r2: float
    rms: Optional[float] = None
    aic: Optional[float] = None
    bic: Optional[float] = None
    n: Optional[int] = None
    slope_per_mps: Optional[complex] = None
    slope_stderr: Optional[Tuple[float, float]] = None

    @classmethod
    def _of(cls, d: Mapping[str, Any]) -> "FormFit":
        return cls(
            form=d["form"],
            eigenvalue=_complex(d["eigenvalue"]),  # type: ignore[arg-type]
            stderr=_pair(d["stderr"]),  # type: ignore[arg-type]
            r2=_float(d["r2"]),
            rms=_opt_float(d.get("rms")),
            aic=_opt_float(d.get("aic")),
            bic=_opt_float(d.get("bic")),
            n=None if d.get("n") is None else int(d["n"]),
            slope_per_mps=_complex(d.get("slope_per_mps")),
            slope_stderr=_pair(d.get("slope_stderr")),
        )


@dataclass(frozen=True)
class FailedFit:
    """A form that could not be fitted to a kick.

    Attributes:
        form: the form's name.
        error: why, in words.
    """

    form: str
    error: str


@dataclass(frozen=True)
class Refusal:
    """Why a fitted eigenvalue is not taken as a measured weave (or a
    speed-varying fit not as the reported one).

    Attributes:
        test: the test it failed (``low_r2``, ``few_periods``,
            ``above_nyquist``, ``not_significant`` ...).
        reason: the same in words, with the numbers.
        numbers: the test's numbers as the JSON gives them (names and
            units of ``docs/measured-runs.md``).
        fit: the fit that was refused, where there is one.
    """

    test: str
    reason: str
    numbers: Dict[str, Any]
    fit: Optional[FormFit]

    @classmethod
    def _of(cls, d: Optional[Mapping[str, Any]]) -> Optional["Refusal"]:
        if d is None:
            return None
        numbers = {k: v for k, v in d.items() if k not in ("test", "reason", "fit")}
        fit = d.get("fit")
        return cls(str(d.get("test", "")), str(d.get("reason", "")), numbers, None if fit is None else FormFit._of(fit))


@dataclass(frozen=True)
class ClockOffset:
    """The offset between a run's speed record and its IMU clock.

    Attributes:
        value: the offset (s).
        stderr: its standard error (s).
        from_data: whether it was estimated from the data (else the
            nominal offset of ``run.toml``).
    """

    value: float
    stderr: Optional[float]
    from_data: bool


@dataclass(frozen=True)
class Kick(_Subscript):
    """One kick of a measured run and its fitted weave eigenvalue
    (``FitResult.kicks``; ``bikedyn fit --json``'s record).

    Attributes:
        run: the run folder or log.
        kick_time: time of the kick on the run's clock (s).
        window: ``(start, end)`` of the free-response window fitted (s).
        window_end: why the window ends (``decayed``, ``next_kick``,
            ``gap``, ``record_end``, ``fall``, ``steer_stop``, ``drift`` ...).
        speed_interval: ``(low, high)`` forward speed over the window (m/s).
        mean_speed: mean forward speed over the window (m/s; NaN without
            a usable speed record).
        weave: the measured weave eigenvalue (1/s), or ``None`` when no
            fit is accepted as a weave (see ``refused``).
        weave_stderr: standard errors of its real and imaginary parts
            ``(re, im)`` (1/s), or ``None``.
        r2: the accepted fit's coefficient of determination, or ``None``.
        form: the accepted fit's form, or ``None``.
        fits: every form fitted to the kick.
        failed_fits: the forms that could not be fitted, with the reason.
        refused: why no fit is a measured weave, or ``None``.
        speed_varying_refused: why a speed-varying fit is not the reported
            one, or ``None``.
        clock_offset: the speed record's clock offset, where there is one.
        predicted_weave: the prediction model's weave eigenvalue at
            ``mean_speed`` (1/s), or ``None``.
        predicted_real_range: range ``(low, high)`` of the predicted real
            part over ``speed_interval`` (1/s), or ``None``.
        predicted_imag_range: range ``(low, high)`` of the predicted
            imaginary part over ``speed_interval`` (rad/s), or ``None``.
        no_prediction: why there is no prediction, or ``None``.
    """

    run: str
    kick_time: float
    window: Tuple[float, float]
    window_end: str
    speed_interval: Tuple[float, float]
    mean_speed: float
    weave: Optional[complex]
    weave_stderr: Optional[Tuple[float, float]]
    r2: Optional[float]
    form: Optional[str]
    fits: Tuple[FormFit, ...]
    failed_fits: Tuple[FailedFit, ...]
    refused: Optional[Refusal]
    speed_varying_refused: Optional[Refusal]
    clock_offset: Optional[ClockOffset]
    predicted_weave: Optional[complex]
    predicted_real_range: Optional[Tuple[float, float]]
    predicted_imag_range: Optional[Tuple[float, float]]
    no_prediction: Optional[str]

    @property
    def speed(self) -> float:
        """``mean_speed`` (m/s)."""
        return self.mean_speed

    @classmethod
    def _of(cls, d: Mapping[str, Any]) -> "Kick":
        p = d.get("predicted_weave")
        c = d.get("clock_offset")
        return cls(
            run=d["run"],
            kick_time=_float(d["kick_time"]),
            window=_pair(d["window"]),  # type: ignore[arg-type]
            window_end=str(d["window_end"]),
            speed_interval=_pair(d["speed_interval"]),  # type: ignore[arg-type]
            mean_speed=_float(d["mean_speed"]),
            weave=_complex(d.get("weave")),
            weave_stderr=_pair(d.get("weave_stderr")),
            r2=_opt_float(d.get("r2")),
            form=d.get("form"),
            fits=tuple(FormFit._of(f) for f in d.get("fits", ())),
            failed_fits=tuple(FailedFit(f["form"], f["error"]) for f in d.get("failed_fits", ())),
            refused=Refusal._of(d.get("refused")),
            speed_varying_refused=Refusal._of(d.get("speed_varying_refused")),
            clock_offset=None
            if c is None
            else ClockOffset(_float(c["value"]), _opt_float(c.get("stderr")), bool(c.get("from_data"))),
            predicted_weave=None if p is None else _complex(p["at_mean_speed"]),
            predicted_real_range=None if p is None else _pair(p["real_range"]),
            predicted_imag_range=None if p is None else _pair(p["imag_range"]),
            no_prediction=d.get("no_prediction"),
        )


@dataclass(frozen=True)
class FitResult(_FromJson):
    """Measured weave eigenvalues of measured runs (``bikedyn.fit``).

    Attributes:
        kicks: one record per kick (run, speed, fitted eigenvalue with
            standard errors, r², the model's prediction).
        skipped: runs left out, each with the reason.
        notes: notes on the runs, each prefixed by its run.
        calibration: the calibration in words (misalignment, noise at rest).
        prediction_model: the generated model that predicts each kick's weave.

    ``to_dict()`` gives the JSON (``kicks`` as ``bikedyn fit --json``
    writes them); ``write_report(dir)`` writes ``kicks.json`` and the fit
    plots (SVG and PNG).
    """

    kicks: Tuple[Kick, ...]
    skipped: Tuple[str, ...]
    notes: Tuple[str, ...]
    calibration: str
    prediction_model: str

    @classmethod
    def _from_raw(cls, raw: Any) -> "FitResult":
        text = raw.json()
        d = json.loads(text)
        out = cls(
            kicks=tuple(Kick._of(k) for k in d["kicks"]),
            skipped=tuple(d.get("skipped", ())),
            notes=tuple(d.get("notes", ())),
            calibration=d.get("calibration", ""),
            prediction_model=d.get("prediction_model", ""),
        )
        return _attach(out, _json=text, _raw=raw)

    def weave_eigenvalues(self) -> Tuple[np.ndarray, np.ndarray]:
        """``(speeds, eigenvalues)`` of the kicks with a measured weave:
        mean speeds (m/s) and weave eigenvalues (1/s, complex)."""
        ks = [k for k in self.kicks if k.weave is not None]
        return (np.array([k.mean_speed for k in ks], dtype=float), np.array([k.weave for k in ks], dtype=complex))

    def write_report(self, directory: PathLike) -> None:
        """Write ``kicks.json`` and the fit plots into ``directory``
        (created if needed)."""
        self._raw.write_report(os.fspath(directory))  # type: ignore[attr-defined]

    def __repr__(self) -> str:
        return (
            f"FitResult(kicks={len(self.kicks)}, skipped={len(self.skipped)}, "
            f"prediction_model={self.prediction_model!r})"
        )


# --------------------------------------------------------------------------
# identify


@dataclass(frozen=True)
class Estimate:
    """A fitted parameter with its standard error and 95 % interval.

    Attributes:
        value: the fitted value (``unit``).
        stderr: its standard error (``unit``).
        low: lower end of the 95 % interval, ``value - 1.96 stderr``.
        high: upper end of the 95 % interval, ``value + 1.96 stderr``.
        confidence: the interval's level: 0.95.
        unit: the unit (SI).
        tied: symbols tied to this one (they take its value).
        prior: ``(mean, sd)`` of the stated prior (a correction of a
            declared-uncertain parameter), or ``None``.
        prior_sds: the value's distance from the prior's mean in prior
            standard deviations, or ``None``.
        on_bound: ``{"floor": x}`` or ``{"ceiling": x}`` when the value
            sits on a bound (a limit, not an estimate), else ``None``.
    """

    value: float
    stderr: float
    low: float
    high: float
    confidence: float = CONFIDENCE
    unit: Optional[str] = None
    tied: Tuple[str, ...] = ()
    prior: Optional[Tuple[float, float]] = None
    prior_sds: Optional[float] = None
    on_bound: Optional[Dict[str, float]] = None

    @classmethod
    def _of_runs(cls, d: Mapping[str, Any]) -> "Estimate":
        p = d.get("prior")
        return cls(
            value=_float(d["value"]),
            stderr=_float(d["stderr"]),
            low=_float(d["low"]),
            high=_float(d["high"]),
            unit=d.get("unit"),
            tied=tuple(d.get("tied") or ()),
            prior=None if p is None else (_float(p["mean"]), _float(p["sd"])),
            prior_sds=_opt_float(d.get("prior_sds")),
            on_bound=d.get("on_bound"),
        )



@dataclass(frozen=True)
class Errors:
    """How far the model's predictions are from the measurements, at one
    stage (before or after identification).

    Attributes:
        eigen_rms: RMS ``|measured - predicted|`` weave eigenvalue over the
            kicks or table rows (1/s); ``None`` where none counts.
        eigen_weighted_rms: the same, each kick weighted by its standard
            errors (1/s); ``None`` for a table.
        roll_rms: pooled RMS roll residual of the simulated runs (rad, or
            rad/s when ``IdentifyResult.roll_channel`` is ``"rate"``);
            ``None`` for a table.
        steer_rms: pooled RMS steer residual (rad); ``None`` for a table.
        speed_rms: pooled RMS speed residual (m/s); ``None`` for a table.
        median_run_roll_rms: median over the runs of the roll RMS (as
            ``roll_rms``); ``None`` for a table and held-out errors.
        median_run_steer_rms: median over the runs of the steer RMS (rad);
            ``None`` for a table and held-out errors.
        held_out: the same errors with each run (or table row) predicted
            by values fitted without it (cross-validation), or ``None``.
    """

    eigen_rms: Optional[float]
    eigen_weighted_rms: Optional[float] = None
    roll_rms: Optional[float] = None
    steer_rms: Optional[float] = None
    speed_rms: Optional[float] = None
    median_run_roll_rms: Optional[float] = None
    median_run_steer_rms: Optional[float] = None
    held_out: Optional["Errors"] = None

    @classmethod
    def _of_runs(cls, d: Mapping[str, Any]) -> "Errors":
        h = d.get("held_out")
        return cls(
            eigen_rms=_opt_float(d.get("eigen_rms")),
            eigen_weighted_rms=_opt_float(d.get("eigen_weighted_rms")),
            roll_rms=_opt_float(d.get("roll_rms")),
            steer_rms=_opt_float(d.get("steer_rms")),
            speed_rms=_opt_float(d.get("speed_rms")),
            median_run_roll_rms=_opt_float(d.get("median_run_roll_rms")),
            median_run_steer_rms=_opt_float(d.get("median_run_steer_rms")),
            held_out=None if h is None else cls._of_runs(h),
        )


@dataclass(frozen=True)
class StageErrors:
    """Time-series errors at one stage of the discovery in the time series.

    Attributes:
        roll_rms: pooled RMS roll residual (rad, or rad/s for a roll-rate
            channel).
        roll_rms_held_out: the same, held out.
        steer_rms: pooled RMS steer residual (rad).
        steer_rms_held_out: the same, held out.
    """

    roll_rms: Optional[float]
    roll_rms_held_out: Optional[float]
    steer_rms: Optional[float]
    steer_rms_held_out: Optional[float]

    @classmethod
    def _of(cls, d: Any) -> Optional["StageErrors"]:
        if not isinstance(d, Mapping) or "roll_rms" not in d:
            return None
        return cls(
            _opt_float(d.get("roll_rms")),
            _opt_float(d.get("roll_rms_held_out")),
            _opt_float(d.get("steer_rms")),
            _opt_float(d.get("steer_rms_held_out")),
        )


def _term_name(t: Mapping[str, Any]) -> str:
    """The runtime's name of a dictionary term (``Term::name`` in
    runtime/src/identify/discovery/dictionary.rs)."""
    kind, of = t["signal"]["kind"], t["signal"].get("of")
    signal = {
        "angle": f"{of}",
        "rate": f"{of}_rate",
        "acceleration": f"{of}_acceleration",
        "controller_torque": "controller",
        "constant": "bias",
        "coulomb": f"coulomb_{of}_rate",
    }.get(kind, kind)
    p = int(t["speed_power"])
    power = "" if p == 0 else "_v" if p == 1 else f"_v{p}"
    return f"{t['equation']}_torque_{signal}{power}{'_lagged' if t['lagged'] else ''}"


def _term_unit(t: Mapping[str, Any]) -> str:
    """The unit of a term's coefficient (``Term::unit``)."""
    base = {
        "angle": "N m/rad",
        "rate": "N m s/rad",
        "acceleration": "kg m^2",
        "controller_torque": "",
        "constant": "N m",
        "coulomb": "N m",
    }.get(t["signal"]["kind"], "")
    p = int(t["speed_power"])
    return base if p == 0 else f"{base} per m/s" if p == 1 else f"{base} per (m/s)^{p}"


@dataclass(frozen=True)
class DiscoveredTerm:
    """A generalized force of the dictionary that the discovery added:
    ``Q_equation += coefficient v^speed_power signal`` (through a
    first-order lag of ``time_constant`` when ``lagged``), benchmark signs
    (roll and steer positive to the right).

    Attributes:
        name: the term's name (``steer_torque_roll_rate_lagged`` ...).
        equation: ``"roll"`` or ``"steer"``: the equation it enters.
        signal: what it multiplies: ``"angle"``, ``"rate"``,
            ``"acceleration"``, ``"controller_torque"``, ``"constant"`` or
            ``"coulomb"``.
        of: the coordinate of ``signal`` (``"roll"``, ``"steer"``), or
            ``None`` (controller torque, constant).
        speed_power: the power of the forward speed it carries (0, 1, 2).
        lagged: whether it acts through a first-order lag.
        coefficient: the fitted coefficient (``unit``), or ``None`` (the
            controller's lag).
        coefficient_stderr: its standard error: one standard error, as the
            reports' ``+-`` on discovered terms (``unit``).
        unit: the coefficient's unit (SI).
        time_constant: a lag's fitted time constant (s), or ``None``.
        time_constant_stderr: its standard error (s), or ``None``.
        alike: names of the step's other terms that explain the data
            alike (BIC within 2): the data do not tell them apart.
    """

    name: str
    equation: str
    signal: str
    of: Optional[str]
    speed_power: int
    lagged: bool
    coefficient: Optional[float]
    coefficient_stderr: Optional[float]
    unit: str
    time_constant: Optional[float]
    time_constant_stderr: Optional[float]
    alike: Tuple[str, ...]

    @classmethod
    def _of(cls, d: Mapping[str, Any]) -> "DiscoveredTerm":
        t = d["term"]
        c, tc = d.get("coefficient"), d.get("time_constant")
        return cls(
            name=_term_name(t),
            equation=t["equation"],
            signal=t["signal"]["kind"],
            of=t["signal"].get("of"),
            speed_power=int(t["speed_power"]),
            lagged=bool(t["lagged"]),
            coefficient=None if c is None else _float(c[0]),
            coefficient_stderr=None if c is None else _float(c[1]),
            unit=_term_unit(t),
            time_constant=None if tc is None else _float(tc[0]),
            time_constant_stderr=None if tc is None else _float(tc[1]),
            alike=tuple(_term_name(a) for a in d.get("alike", ())),
        )


@dataclass(frozen=True)
class Discovery(_Subscript):
    """What the search of the dictionary of generalized forces found beyond
    the library (``IdentifyResult.discovery``: on the weave eigenvalues of
    the kicks or table; ``IdentifyResult.time_series_discovery``: in the
    time series).

    Attributes:
        status: ``"ran"`` or ``"not_run"``.
        reason: why it did not run, or ``None``.
        terms: the terms added, in order.
        readings: each added term in physical words.
        rms_library: weave eigenvalue RMS error with the library alone
            (1/s); eigenvalue discovery only, else ``None``.
        rms_after: the same with the discovered terms (1/s), or ``None``.
        rms_library_held_out: with the library alone, held out (1/s), or
            ``None``.
        rms_held_out: with the terms, held out (1/s), or ``None``.
        base: time-series errors of the base model (time-series discovery
            only, else ``None``).
        library: time-series errors with the library's selection, or ``None``.
        after: time-series errors with the terms added, or ``None``.
    """

    status: str
    reason: Optional[str]
    terms: Tuple[DiscoveredTerm, ...]
    readings: Tuple[str, ...]
    rms_library: Optional[float] = None
    rms_after: Optional[float] = None
    rms_library_held_out: Optional[float] = None
    rms_held_out: Optional[float] = None
    base: Optional[StageErrors] = None
    library: Optional[StageErrors] = None
    after: Optional[StageErrors] = None

    @property
    def ran(self) -> bool:
        """Whether the search ran."""
        return self.status == "ran"

    @classmethod
    def _of(cls, d: Optional[Mapping[str, Any]]) -> Optional["Discovery"]:
        if d is None:
            return None
        return cls(
            status=str(d.get("status")),
            reason=d.get("reason"),
            terms=tuple(DiscoveredTerm._of(t) for t in d.get("terms", ())),
            readings=tuple(d.get("readings", ())),
            rms_library=_opt_float(d.get("rms_library")),
            rms_after=_opt_float(d.get("rms_after")),
            rms_library_held_out=_opt_float(d.get("rms_library_held_out")),
            rms_held_out=_opt_float(d.get("rms_held_out")),
            base=StageErrors._of(d.get("base")),
            library=StageErrors._of(d.get("library")),
            after=StageErrors._of(d.get("with_terms")),
        )


@dataclass(frozen=True)
class IdentifyResult(_FromJson):
    """What identification found (``bikedyn.identify``): from measured runs
    (``source == "runs"``, the JSON of ``bikedyn identify --json``) or from
    a table of measured weave eigenvalues (``source ==
    "eigenvalue_table"``, ``identify --eigenvalues``).

    Attributes:
        source: ``"runs"`` or ``"eigenvalue_table"``.
        selected: the selected effects and parameter corrections, in order
            of selection (also ``selected_effects``).
        parameters: the fitted value of each selected symbol, with its
            standard error and 95 % interval (``value +- 1.96 stderr``).
        error_before: the errors of the base model; ``held_out`` of the
            runs' is the base model's time series cross-validated.
        error_after: the errors with the selection; ``held_out``: each run
            (or table row) predicted with the values fitted without it.
        model: the model fitted (runs: the free-speed model; a table: the
            driven-speed model).
        driven_model: the driven-speed model of the weave predictions.
        discovery: what the dictionary of generalized forces found on the
            weave eigenvalues (kicks or table rows) beyond the library, or
            ``None`` (``discover=False``).
        time_series_discovery: the same in the time series (runs only),
            or ``None``.
        skipped: runs and kicks left out, each with the reason (runs only).
        kicks: the kicks fitted (runs), or ``None``.
        table: the table read (a table), or ``None``.
        rows: the table's rows (a table), or ``None``.
        roll_channel: what the runs' roll channel measures, ``"angle"`` or
            ``"rate"`` (runs), or ``None``.
        not_tried: candidates not tried, each ``(name, reason)`` (a table).

    ``summary()`` is the console summary, ``write_report(dir)`` writes the
    report (report.md, JSON, plots) and ``to_dict()`` the full JSON as the
    command line prints it (candidates, verdicts, per-run errors,
    diagnosis ...).
    """

    source: str
    selected: Tuple[str, ...]
    parameters: Dict[str, Estimate]
    error_before: Errors
    error_after: Errors
    model: str
    driven_model: str
    discovery: Optional[Discovery]
    time_series_discovery: Optional[Discovery]
    skipped: Tuple[str, ...]
    kicks: Optional[int]
    table: Optional[str]
    rows: Optional[int]
    roll_channel: Optional[str]
    not_tried: Tuple[Tuple[str, str], ...]

    @property
    def selected_effects(self) -> Tuple[str, ...]:
        """``selected`` (the name of ``bikedyn identify --json``)."""
        return self.selected

    @classmethod
    def _from_json(cls, raw: Any) -> "IdentifyResult":
        """Runs, logs and tables share one JSON schema
        (``src/identify/result.rs``); ``source`` says which it was."""
        text = raw.json()
        d = json.loads(text)
        table = d["source"] == "eigenvalue_table"
        out = cls(
            source=str(d["source"]),
            selected=tuple(d["selected_effects"]),
            parameters={k: Estimate._of_runs(v) for k, v in d["parameters"].items()},
            error_before=Errors._of_runs(d["error_before"]),
            error_after=Errors._of_runs(d["error_after"]),
            model=d["driven_model"] if table else d["model"],
            driven_model=d["driven_model"],
            discovery=Discovery._of(d.get("discovery")),
            time_series_discovery=Discovery._of(d.get("time_series_discovery")),
            skipped=tuple(d.get("skipped", ())),
            kicks=None if table else int(d["kicks"]),
            table=str(d["table"]) if table else None,
            rows=len(d["points"]) if table else None,
            roll_channel=d.get("roll_channel"),
            not_tried=tuple((str(n), str(w)) for n, w in d.get("not_tried", ())),
        )
        return _attach(out, _json=text, _raw=raw)

    def summary(self) -> str:
        """The console summary of ``bikedyn identify``."""
        return str(self._raw.summary())  # type: ignore[attr-defined]

    def write_report(self, directory: PathLike) -> None:
        """Write the report files into ``directory`` (created if needed)."""
        self._raw.write_report(os.fspath(directory))  # type: ignore[attr-defined]

    def __repr__(self) -> str:
        values = {k: e.value for k, e in self.parameters.items()}
        return f"IdentifyResult(source={self.source!r}, selected={list(self.selected)!r}, parameters={values!r})"
