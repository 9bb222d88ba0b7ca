"""Scene files: TOML load/save, presets, dotted-path overrides, and one-line error messages.

Every error a user can cause is a :class:`SceneError` whose message names the field (as a dotted
path such as ``leds.height_mm``) and the offending value.
"""

from __future__ import annotations

import copy
import math
import tomllib
import warnings
from importlib import resources
from pathlib import Path
from typing import Any

import tomli_w
from pydantic import ValidationError

from eyelume.errors import EyelumeWarning, GeometryError, SceneError
from eyelume.scene.eye import check_eye_geometry
from eyelume.scene.model import QE_CURVES, RING_FIELDS, LedArray, Scene
from eyelume.scene.textfile import decode_text

__all__ = [
    "SceneError",
    "apply_overrides",
    "load_scene",
    "not_a_path",
    "preset_names",
    "save_scene",
    "validation_error",
]

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


def _format_loc(loc: tuple[Any, ...], data: Any = None, brackets: bool = False) -> str:
    """A pydantic error location as the user's field: without pydantic's own tags (validator
    functions, and the member of a union such as ``float | list[float]`` or ``Literal['sensor']
    | float`` that was tried), found by walking ``data`` (the validated input) along it — a
    name that is a key of the table there is a field, whatever it is called. Dotted as a scene
    path (``elements.0.front``, what ``--set`` takes), or with ``brackets`` as a TOML file reads
    (``vary[0].range[1]``)."""
    parts: list[Any] = []
    node = data
    for part in loc:
        if isinstance(part, int):
            parts.append(part)
            ok = isinstance(node, list | tuple) and -len(node) <= part < len(node)
            node = node[part] if ok else None
        elif isinstance(node, dict) and part in node:
            parts.append(part)
            node = node[part]
        elif not (_is_tag(part) or (isinstance(node, dict) and part[:1].isupper())) and (
            node is None or isinstance(node, dict)
        ):
            parts.append(part)  # a field absent from the input (required, or beyond it)
            node = None
    if not brackets:
        return ".".join(str(p) for p in parts)
    text = ""
    for p in parts:
        text += f"[{p}]" if isinstance(p, int) else (f".{p}" if text else str(p))
    return text


#: Union members pydantic names by their type (``float | list[float]`` → "float", "list[float]").
_TYPE_TAGS = frozenset({"bool", "bytes", "dict", "float", "int", "list", "none", "str", "tuple"})


def _is_tag(part: Any) -> bool:
    return isinstance(part, str) and (
        part in _TYPE_TAGS
        or part.startswith(("function-", "constrained-", "is-instance[", "lax-or-strict["))
        or part.startswith(("list[", "tuple[", "literal[", "dict[", "set[", "nullable["))
    )


def _union_choice(loc: tuple[Any, ...]) -> int | None:
    """The position in ``loc`` of the union member tried (a type tag or a model's class name),
    or None."""
    for i, part in enumerate(loc):
        if (
            isinstance(part, str)
            and not part.startswith(("function-", "constrained-"))
            and (_is_tag(part) or part[:1].isupper())
        ):
            return i
    return None


def _first_error(errors: list[dict]) -> tuple[dict, str]:
    """(the error to report, its message). Pydantic reports a value that fits no member of a
    union once per member; the member with the fewest errors, then the one that got deepest
    into the value, is what the user meant (a range [[1, 2], [3, "a"]] is a list of pairs with
    one bad number, not a pair of bad numbers). When
    the members tie with one error each at the same place, their wants are joined ("Input
    should be 'sensor' or a valid number")."""
    first = errors[0]
    msg = first["msg"].removeprefix("Value error, ")
    i = _union_choice(tuple(first["loc"]))
    if i is None:
        return first, msg
    prefix = tuple(first["loc"][:i])
    members: dict[Any, list[dict]] = {}
    for e in errors:
        loc = tuple(e["loc"])
        if loc[:i] == prefix and len(loc) > i and _union_choice(loc) == i:
            members.setdefault(loc[i], []).append(e)
    best = min(members.values(), key=lambda v: (len(v), -len(v[0]["loc"])))
    chosen = best[0]
    msg = chosen["msg"].removeprefix("Value error, ")
    single = [v[0] for v in members.values() if len(v) == 1]
    if len(best) == 1 and len(single) > 1 and len({tuple(e["loc"][i + 1 :]) for e in single}) == 1:
        wants = [e["msg"].removeprefix("Value error, ") for e in single]
        if all(w.startswith("Input should be ") for w in wants):
            msg = " or ".join([wants[0], *(w.removeprefix("Input should be ") for w in wants[1:])])
    return chosen, msg


def validation_error(exc: ValidationError, data: Any, origin: str, brackets: bool = False):
    """The first problem of pydantic's ``exc`` as one-line SceneError naming ``origin`` (the
    file), the user's field (:func:`_format_loc`: dotted, or with ``brackets`` as in a TOML
    input file) and the value they gave; an unknown field and a missing one said so. The one
    formatter of every validated input: scenes, population files, study and dataset files."""
    err, msg = _first_error(exc.errors())
    loc = tuple(err["loc"])
    field = _format_loc(loc, data, brackets) or "(top level)"
    if err["type"] == "extra_forbidden":
        return SceneError("unknown field", file=origin, field=field)
    if err["type"] == "missing":
        return SceneError("is required", file=origin, field=field)
    value = err.get("input", _lookup(data, loc))
    if field == "(top level)":
        return SceneError(f"{origin}: {msg}")
    if isinstance(value, dict):
        return SceneError(f"{origin}: {field}: {msg}")
    return SceneError(msg, file=origin, field=field, value=value)


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
    GeometryError naming ``origin``, the field and the value) and a lens glass missing from
    its catalogs (:func:`_check_glasses`, SceneError naming the same)."""
    try:
        scene = Scene.model_validate(data)
    except ValidationError as exc:
        raise validation_error(exc, data, origin) from None
    try:
        check_eye_geometry(scene.eye)
    except GeometryError as exc:
        raise GeometryError(exc.message, file=origin, field=exc.field, value=exc.value) from None
    _check_glasses(scene, origin)
    return scene


def _check_glasses(scene: Scene, origin: str) -> None:
    """SceneError naming ``origin`` (the file), the field and the glass when a lens surface's
    glass is in none of the lens's catalogs (or a catalog cannot be read) — said when the
    scene is read, not later when it is compiled (:func:`eyelume.compile.lens_indices`, which
    checks again for scenes built in code)."""
    from eyelume.errors import GlassError
    from eyelume.scene.glass import load_catalog

    lens = scene.lens
    if lens is None or not any(s.glass and s.glass.lower() != "air" for s in lens.surfaces):
        return
    try:
        catalog = load_catalog(*lens.glass_catalogs) if lens.glass_catalogs else load_catalog()
    except GlassError as exc:
        raise SceneError(str(exc), file=origin, field="lens.glass_catalogs") from None
    for j, s in enumerate(lens.surfaces):
        if s.glass and s.glass.lower() != "air":
            try:
                catalog[s.glass]
            except GlassError as exc:
                raise SceneError(
                    str(exc), file=origin, field=f"lens.surfaces.{j}.glass", value=s.glass
                ) from None


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
    return _validate_overridden(data, origin, overrides)


def _validate_overridden(data: dict[str, Any], origin: str, overrides: dict[str, Any] | None):
    """:func:`validate_scene`, an unknown field that an override made named as that override's
    (``--set leds.hieght=3``: "override 'leds.hieght': …", not the preset's or file's)."""
    try:
        return validate_scene(data, origin)
    except SceneError as exc:
        for key in overrides or ():
            if exc.message == "unknown field" and not_a_path(exc, key):
                raise SceneError(
                    f"override '{key}': the scene ({origin}) has no field '{exc.field}'"
                ) from None
        raise


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


def _drop_length_for_spheres(data: dict[str, Any], overrides: dict[str, Any]) -> None:
    """An override that makes every LED's body a sphere (``leds.body_shape = "sphere"``) drops
    the scene's ``body_length_mm``, a cylinder's length that a sphere has no use for (its
    length is its diameter), with a one-line :class:`~eyelume.errors.EyelumeWarning` naming
    the value dropped — unless ``leds.body_length_mm`` is overridden too (then it is refused
    beside spheres, as in a file, where both are written by the same hand)."""
    leds = data.get("leds")
    if (
        "leds.body_shape" not in overrides
        or "leds.body_length_mm" in overrides
        or not isinstance(leds, dict)
        or leds.get("body_length_mm") is None
    ):
        return
    shape = _parse_value(overrides["leds.body_shape"])
    shapes = shape if isinstance(shape, list) else [shape]
    if shapes and all(s == "sphere" for s in shapes):
        length = leds.pop("body_length_mm")
        warnings.warn(
            f"leds.body_shape = 'sphere' set: the scene's leds.body_length_mm = {length!r} (a "
            "cylinder's length) is dropped; a sphere is body_diameter_mm = "
            f"{leds.get('body_diameter_mm', LedArray.model_fields['body_diameter_mm'].default)!r}"
            " across",
            EyelumeWarning,
            stacklevel=4,
        )


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
    _drop_length_for_spheres(data, overrides)
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


def not_a_path(exc: Exception, path: str) -> bool:
    """Whether ``exc``, raised by :func:`apply_overrides` with an override of ``path``, is about
    the path itself — not a dotted path, no such item, no such field (or table) of the scene —
    rather than about the value given to it."""
    if not isinstance(exc, SceneError):
        return False
    if exc.field is None and exc.message.startswith(f"override '{path}'"):
        return True
    return exc.message == "unknown field" and (
        exc.field == path or path.startswith(f"{exc.field}.")
    )


def apply_overrides(scene: Scene, overrides: dict[str, Any]) -> Scene:
    """A new scene with the dotted-path ``overrides`` applied (the scene itself is unchanged)."""
    data = scene.model_dump(mode="python")
    return _validate_overridden(_override_data(data, overrides), f"scene {scene.name}", overrides)


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
