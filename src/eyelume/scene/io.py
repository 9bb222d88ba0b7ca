"""Scene files: TOML load/save, presets, dotted-path overrides, and one-line error messages.

Every error a user can cause is a :class:`SceneError` whose message names the field (as a dotted
path such as ``leds.height_mm``) and the offending value.
"""

from __future__ import annotations

import copy
import math
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

import tomli_w
from pydantic import ValidationError

from eyelume.errors import GeometryError, SceneError
from eyelume.scene.eye import check_eye_geometry
from eyelume.scene.model import QE_CURVES, RING_FIELDS, Scene
from eyelume.scene.textfile import decode_text

__all__ = ["SceneError", "apply_overrides", "load_scene", "preset_names", "save_scene"]

_PRESETS = "eyelume.scene.presets"


def preset_names() -> list[str]:
    """Names of the scenes shipped with eyelume (``paper2005``, …)."""
    root = resources.files(_PRESETS)
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def _read_toml(path: Path) -> dict[str, Any]:
    """The scene file's TOML. TOML is UTF-8 (with or without a BOM); a file an editor saved as
    UTF-16 or Windows-1252 is read too (:func:`~eyelume.scene.textfile.decode_text`)."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise SceneError(f"cannot read scene file '{path}': {exc.strerror}") from None
    text = decode_text(raw, path, SceneError).lstrip("\ufeff")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"scene file '{path}' is not valid TOML: {exc}") from None


def _resolve_paths(data: dict[str, Any], base: Path) -> None:
    """Make file references in the scene absolute, relative to the scene file's folder."""
    leds = data.get("leds")
    profile = leds.get("profile") if isinstance(leds, dict) else None
    if isinstance(profile, dict) and isinstance(profile.get("table_csv"), str):
        profile["table_csv"] = _resolved(base, profile["table_csv"], "leds.profile.table_csv")
    for k, item in enumerate(profile if isinstance(profile, list) else []):
        if isinstance(item, dict) and isinstance(item.get("table_csv"), str):
            item["table_csv"] = _resolved(base, item["table_csv"], f"leds.profile.{k}.table_csv")
    for k, el in enumerate(data.get("elements") or []):
        for side in ("front", "back"):
            surf = el.get(side) if isinstance(el, dict) else None
            coat = surf.get("coating") if isinstance(surf, dict) else None
            if isinstance(coat, dict) and isinstance(coat.get("table_csv"), str):
                field = f"elements.{k}.{side}.coating.table_csv"
                coat["table_csv"] = _resolved(base, coat["table_csv"], field)
    sensor = data.get("sensor")
    qe = sensor.get("quantum_efficiency") if isinstance(sensor, dict) else None
    if isinstance(qe, str) and qe.strip() and qe not in QE_CURVES:
        sensor["quantum_efficiency"] = _resolved(base, qe, "sensor.quantum_efficiency")
    filt = sensor.get("filter") if isinstance(sensor, dict) else None
    if (
        isinstance(filt, dict)
        and isinstance(filt.get("table_csv"), str)
        and filt["table_csv"].strip()
    ):
        filt["table_csv"] = _resolved(base, filt["table_csv"], "sensor.filter.table_csv")
    lens = data.get("lens")
    if isinstance(lens, dict) and isinstance(lens.get("glass_catalogs"), list):
        lens["glass_catalogs"] = [
            _resolved(base, p, f"lens.glass_catalogs.{i}") if isinstance(p, str) else p
            for i, p in enumerate(lens["glass_catalogs"])
        ]


def _resolved(base: Path, name: str, field: str) -> str:
    """``name`` relative to ``base``, absolute; SceneError naming ``field`` if it is no path."""
    try:
        return str((base / name).resolve())
    except (OSError, ValueError) as exc:
        raise SceneError(f"not a usable file path ({exc})", field=field, value=name) from None


def _format_loc(loc: tuple[Any, ...]) -> str:
    """A pydantic error location as a dotted scene path, without pydantic's own tags (validator
    functions, and the member of a union such as ``float | list[float]`` that was tried)."""
    return ".".join(str(p) for p in loc if not _is_tag(p))


def _is_tag(part: Any) -> bool:
    return isinstance(part, str) and (
        part.startswith("function-") or part.startswith("constrained-") or part.startswith("list[")
    )


def _lookup(data: Any, loc: tuple[Any, ...]) -> Any:
    for part in loc:
        try:
            data = data[part]
        except (KeyError, IndexError, TypeError):
            return None
    return data


def validate_scene(data: dict[str, Any], origin: str = "scene") -> Scene:
    """Build a :class:`Scene` from plain data, turning the first validation error into one line;
    then refuse an eye that cannot exist (:func:`~eyelume.scene.eye.check_eye_geometry`,
    GeometryError naming ``origin``, the field and the value)."""
    try:
        scene = Scene.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = tuple(err["loc"])
        field = _format_loc(loc) or "(top level)"
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            raise SceneError("unknown field", file=origin, field=field) from None
        if err["type"] == "missing":
            raise SceneError("is required", file=origin, field=field) from None
        value = err.get("input", _lookup(data, loc))
        if not loc:
            raise SceneError(f"{origin}: {msg}") from None
        if isinstance(value, dict):
            raise SceneError(f"{origin}: {field}: {msg}") from None
        raise SceneError(msg, file=origin, field=field, value=value) from None
    try:
        check_eye_geometry(scene.eye)
    except GeometryError as exc:
        raise GeometryError(exc.message, file=origin, field=exc.field, value=exc.value) from None
    return scene


def load_scene(source: str | Path = "paper2005", overrides: dict[str, Any] | None = None) -> Scene:
    """Load a scene from a preset name or a TOML file, then apply dotted-path overrides.

    Parameters
    ----------
    source
        A preset name (see :func:`preset_names`) or the path of a ``.toml`` scene file.
    overrides
        ``{"leds.height_mm": 40, ...}``; values may be TOML literals given as strings.

    Examples
    --------
    >>> scene = load_scene("paper2005", {"leds.height_mm": "40"})
    >>> scene.leds.height_mm
    40.0
    """
    text_source = str(source)
    if text_source in preset_names():
        res = resources.files(_PRESETS) / f"{text_source}.toml"
        with resources.as_file(res) as path:
            data = _read_toml(path)
            _resolve_paths(data, path.parent)
        origin = f"preset {text_source}"
    else:
        path = Path(text_source)
        if not path.exists():
            raise SceneError(
                f"scene '{text_source}' is neither a file nor a preset "
                f"(presets: {', '.join(preset_names())})"
            )
        data = _read_toml(path)
        _resolve_paths(data, path.parent)
        origin = str(path)
    if overrides:
        data = _override_data(data, overrides)
    return validate_scene(data, origin)


def _parse_value(text: Any) -> Any:
    """A TOML literal (``40``, ``true``, ``[1, 2]``, ``"x"``, ``inf``) or else the bare string."""
    if not isinstance(text, str):
        return text
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def _drop_ring_for_positions(data: dict[str, Any], overrides: dict[str, Any]) -> None:
    """LEDs placed one by one by an override replace the ring: its fields go, unless overridden
    too (then they are refused beside positions_mm, as in a file)."""
    leds = data.get("leds")
    if "leds.positions_mm" in overrides and isinstance(leds, dict):
        for name in RING_FIELDS:
            leds.pop(name, None)


#: The eye's fields a library eye model supplies (:class:`~eyelume.scene.model.Eye`).
_EYE_MODEL_FIELDS = ("surfaces", "iris_surface", "dispersion", "reference_wavelength_nm")


def _drop_eye_for_model(data: dict[str, Any], overrides: dict[str, Any]) -> None:
    """An override that names another eye model (``eye.model``) takes that model's surfaces,
    pupil and dispersion from the library: the scene's written ones go, unless overridden too."""
    eye = data.get("eye")
    if "eye.model" not in overrides or not isinstance(eye, dict):
        return
    for name in _EYE_MODEL_FIELDS:
        if not any(k == f"eye.{name}" or k.startswith(f"eye.{name}.") for k in overrides):
            eye.pop(name, None)


def _table_in(node: dict[str, Any], part: str) -> Any:
    """``node[part]``, made an empty table when absent or None (``ambient.sun`` of a scene
    without a sun: ``--set ambient.sun.elevation_deg=40`` makes one)."""
    if node.get(part) is None:
        node[part] = {}
    return node[part]


def _override_data(data: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    data = copy.deepcopy(data)
    _drop_ring_for_positions(data, overrides)
    _drop_eye_for_model(data, overrides)
    for key, raw in overrides.items():
        parts = key.split(".")
        if not key or any(p == "" for p in parts):
            raise SceneError(f"override '{key}': not a dotted field path like leds.height_mm")
        node: Any = data
        for i, part in enumerate(parts[:-1]):
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise SceneError(f"override '{key}': no item {part} in '{'.'.join(parts[:i])}'")
                node = node[int(part)]
            else:
                node = _table_in(node, part)
            if not isinstance(node, dict | list):
                raise SceneError(f"override '{key}': '{'.'.join(parts[: i + 1])}' is not a table")
        last = parts[-1]
        value = _parse_value(raw)
        if isinstance(value, float) and math.isnan(value):
            raise SceneError(f"override '{key}' = nan: must be a number, not NaN")
        if isinstance(node, list):
            if not last.isdigit() or int(last) >= len(node):
                raise SceneError(f"override '{key}': no item {last} in this list")
            node[int(last)] = value
        else:
            node[last] = value
    return data


def apply_overrides(scene: Scene, overrides: dict[str, Any]) -> Scene:
    """A new scene with the dotted-path ``overrides`` applied (the scene itself is unchanged)."""
    data = scene.model_dump(mode="python")
    return validate_scene(_override_data(data, overrides), f"scene {scene.name}")


def _toml_ready(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _toml_ready(v) for k, v in value.items() if v is not None}
    if isinstance(value, list | tuple):
        return [_toml_ready(v) for v in value]
    return value


def save_scene(scene: Scene, path: str | Path) -> None:
    """Write a scene as TOML that :func:`load_scene` reads back to an equal scene."""
    data = _toml_ready(scene.model_dump(mode="python"))
    Path(path).write_text(tomli_w.dumps(data), encoding="utf-8")
