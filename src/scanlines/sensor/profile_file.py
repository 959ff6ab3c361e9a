"""A sensor profile's file read as data to distrust: its fields checked, the file bounded.

:func:`read_values` reads the JSON of a profile file (a regular file of at most
:data:`MAX_PROFILE_BYTES`, nested a few levels deep: ``scanlines.untrusted``);
:func:`checked_fields` checks the values :meth:`~scanlines.sensor.profile.SensorProfile.
to_dict` writes: numbers are numbers (not booleans), counts are counts, the noise line
finite, not negative and at most :data:`MAX_NOISE_SIGMA0` + :data:`MAX_NOISE_PER_METRE` x
range. Each mistake is a :class:`ProfileError` of one line naming the file and the field.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from scanlines.errors import NO_SUCH_FILE, ScanlinesError, describe
from scanlines.untrusted import UntrustedInput, clip, load_json, quote, read_regular_file

__all__ = [
    "MAX_NOISE_PER_METRE",
    "MAX_NOISE_SIGMA0",
    "MAX_PROFILE_BYTES",
    "PROFILE_FORMAT",
    "ProfileError",
    "checked_fields",
    "read_values",
]

PROFILE_FORMAT = "scanlines-sensor-profile/1"


class ProfileError(ScanlinesError, ValueError):
    """A sensor profile file is missing, malformed or unusable."""


def checked_fields(values: Any, where: str, known: tuple[str, ...]) -> dict[str, Any]:
    """The fields of a profile (``known``: its dataclass's) from a file's ``values``,
    checked and converted (``noise_bins`` as ``(range, sigma, error, samples)`` tuples)."""
    if not isinstance(values, dict) or values.get("format") != PROFILE_FORMAT:
        raise ProfileError(f"{where}: not a sensor profile (format {PROFILE_FORMAT!r})")
    unknown = sorted(map(str, set(values) - set(known) - {"format"}))
    if unknown:
        raise ProfileError(f"{where}: unknown field(s) {clip(', '.join(unknown))}")
    kwargs = {k: v for k, v in values.items() if k in known}
    for key in ("noise_sigma0", "noise_per_metre"):
        if key not in kwargs:
            raise ProfileError(f"{where}: field {key!r} is missing")
    for key, value in list(kwargs.items()):
        if key not in _NOT_NUMBERS:
            kwargs[key] = _number(value, f"{where}: field {key!r}")
    _check_noise_line(kwargs["noise_sigma0"], kwargs["noise_per_metre"], where)
    for key in ("beams", "scans"):
        if not _is_count(kwargs.get(key, 0)):
            got = quote(kwargs[key])
            raise ProfileError(f"{where}: field {key!r} must be a count, got {got}")
    if not isinstance(kwargs.get("source", ""), str):
        raise ProfileError(f"{where}: field 'source' must be a string")
    kwargs["noise_bins"] = _noise_bins_of(kwargs.get("noise_bins", []), where)
    kwargs["mounting"] = _mounting_of(kwargs.get("mounting"), where)
    codes = kwargs.get("no_return_codes", {})
    if not isinstance(codes, dict):
        raise ProfileError(f"{where}: field 'no_return_codes' must map codes to shares")
    kwargs["no_return_codes"] = {
        clip(str(k)): _number(v, f"{where}: no_return_codes") for k, v in codes.items()
    }
    return kwargs


#: The largest noise line a profile file may hold: 1 m + 100 % of the range. A scanner
#: noisier than that measures nothing; past it the covariances of every feature overflow.
MAX_NOISE_SIGMA0 = 1.0
MAX_NOISE_PER_METRE = 1.0
#: Largest sensor profile file read (one is about 2 KB).
MAX_PROFILE_BYTES = 1 << 20
_NOT_NUMBERS = ("noise_bins", "no_return_codes", "mounting", "source", "beams", "scans")


def _number(value: Any, what: str) -> float:
    """``value`` as a float (``"nan"``, ``"inf"`` as written by :meth:`SensorProfile.to_dict`),
    a boolean or anything else not a number refused."""
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise ProfileError(f"{what} must be a number, got {quote(value)}")
    try:
        return float(value)
    except (TypeError, ValueError, OverflowError):
        raise ProfileError(f"{what} must be a number, got {quote(value)}") from None


def _is_count(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= 1 << 40


def _check_noise_line(sigma0: float, per_metre: float, where: str) -> None:
    if not (0.0 <= sigma0 <= MAX_NOISE_SIGMA0 and 0.0 <= per_metre <= MAX_NOISE_PER_METRE):
        raise ProfileError(
            f"{where}: the noise line {quote(sigma0)} m + {quote(per_metre)} x range must be "
            f"finite, not negative and at most {MAX_NOISE_SIGMA0:g} m + "
            f"{100 * MAX_NOISE_PER_METRE:g} % of range"
        )


def _noise_bins_of(bins: Any, where: str) -> tuple[tuple[float, float, float, int], ...]:
    if not isinstance(bins, list) or not all(isinstance(b, dict) for b in bins):
        raise ProfileError(f"{where}: field 'noise_bins' must be a list of bins")
    out = []
    for k, values in enumerate(bins):
        if set(values) != {"range", "sigma", "error", "samples"}:
            fields = clip(", ".join(map(str, values)))
            raise ProfileError(
                f"{where}: noise bin {k}: fields range, sigma, error, samples, got {fields}"
            )
        numbers = {name: _number(values[name], f"{where}: noise bin {k}: {name}")
                   for name in ("range", "sigma", "error")}  # fmt: skip
        if not _is_count(values["samples"]):
            raise ProfileError(f"{where}: noise bin {k}: samples must be a count")
        out.append((numbers["range"], numbers["sigma"], numbers["error"], values["samples"]))
    return tuple(out)


def _mounting_of(mounting: Any, where: str) -> tuple[float, float, float] | None:
    if mounting is None:
        return None
    if not isinstance(mounting, list) or len(mounting) != 3:
        raise ProfileError(f"{where}: field 'mounting' must be [x, y, theta] or null")
    x, y, theta = (_number(v, f"{where}: field 'mounting'") for v in mounting)
    return (x, y, theta)


def read_values(path: str | Path) -> Any:
    """The JSON values of the profile file ``path``: a regular file of at most
    :data:`MAX_PROFILE_BYTES`, nested at most a few levels deep."""
    path = Path(path)
    try:
        return load_json(read_regular_file(path, MAX_PROFILE_BYTES))
    except FileNotFoundError:
        raise ProfileError(f"{path}: {NO_SUCH_FILE}") from None
    except OSError as error:
        reason = error.strerror or describe(error)
        raise ProfileError(f"{path}: cannot read the sensor profile: {reason}") from None
    except UntrustedInput as error:
        raise ProfileError(f"{path}: not a sensor profile: {error}") from None
    except UnicodeDecodeError as error:
        raise ProfileError(f"{path}: not a sensor profile: not UTF-8 ({error.reason})") from None
    except json.JSONDecodeError as error:
        raise ProfileError(
            f"{path}: not a sensor profile: not JSON ({error.msg}, line {error.lineno})"
        ) from None
    except ValueError as error:  # an integer too long for Python to convert
        raise ProfileError(f"{path}: not a sensor profile: {describe(error)}") from None
