"""The scene: plain validated data describing LEDs, eye, face, imaging lens, sensor and receivers.

No physics happens here. Every length is in millimetres, every angle in degrees, wavelength in
nanometres, radiant intensity in W/sr (ARCHITECTURE.md §2). The world (headset) frame has +z from
the eye toward the camera and LEDs, +y up, and the anterior corneal vertex of the eye in primary
gaze at the eye's pose (:class:`EyePose`; the origin by default), as written for a right eye;
the eye's prescription is written in its own lens-design frame (z' into the eye, z' = −z in
primary gaze).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal, get_args

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_serializer,
    model_validator,
)

from eyelume.scene.eye_models import DISPERSION_RANGE_NM, eye_model_data, eye_model_names

__all__ = [
    "Ambient",
    "Camera",
    "CameraBody",
    "Eye",
    "EyePlane",
    "EyePose",
    "EyeSurface",
    "Coating",
    "Element",
    "ElementSurface",
    "Face",
    "IdealLens",
    "ImagingLens",
    "Lashes",
    "LedArray",
    "LedProfile",
    "LED_BODY_SHAPES",
    "LensSurface",
    "PER_LED_NUMBERS",
    "QE_CURVES",
    "RING_FIELDS",
    "Run",
    "Scene",
    "Sensor",
    "SensorFilter",
    "SOLAR_SPECTRA",
    "Sun",
    "Tissue",
    "WAVELENGTH_RANGE_NM",
]


def _not_nan(value: float) -> float:
    if math.isnan(value):
        raise ValueError("must be a number, not NaN")
    return value


#: A radius of curvature: finite and non-zero, or ±inf for a plane.
Radius = Annotated[float, Field(allow_inf_nan=True), AfterValidator(_not_nan)]
#: Largest magnitude of a scene quantity (mm, W/sr, ...): nothing in a head-mounted eye tracker
#: comes near 10⁶ of its unit; larger is a typo, and 1e300 overflowed squares in the geometry and
#: the statistics (raw NumPy warnings, a NaN variance) instead of a one-line refusal.
MAX_MAGNITUDE = 1e6
Positive = Annotated[float, Field(gt=0, le=MAX_MAGNITUDE)]
NonNegative = Annotated[float, Field(ge=0, le=MAX_MAGNITUDE)]
Fraction = Annotated[float, Field(ge=0, le=1)]
_Coordinate = Annotated[float, Field(ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)]
Vector3 = tuple[_Coordinate, _Coordinate, _Coordinate]


#: The wavelengths a scene and its LEDs may have (nm): the near ultraviolet to the short-wave
#: infrared. The eye's indices (from its d, F, C values) and a glass's (its catalog formula) are
#: evaluated anywhere in it; a glass whose catalog range is narrower gets a warning at compile.
WAVELENGTH_RANGE_NM = (300.0, 2500.0)

#: Built-in sensor QE(λ) curves (``sensor.quantum_efficiency = "<name>"``): name → file in
#: ``eyelume/scene/presets/sensors/`` (each file states its source).
QE_CURVES = {"nir-global-shutter": "nir-global-shutter.csv"}

#: The sunlight spectra ``ambient.sun.spectrum`` names: name → column of the ASTM G173-03 table
#: ``eyelume/scene/presets/solar/astm_g173_03.csv`` (W m⁻² nm⁻¹; its source in the file).
SOLAR_SPECTRA = {
    "am1.5-direct": "direct_circumsolar_w_m2_nm",
    "am1.5-global": "global_tilt_w_m2_nm",
}

#: The per-LED numeric fields of :class:`LedArray`: one value for every LED, or one per LED.
PER_LED_NUMBERS = (
    "radiant_intensity_w_sr",
    "wavelength_nm",
    "body_diameter_mm",
    "body_length_mm",
    "emitter_diameter_mm",
)

#: The LED body shapes :class:`LedArray` knows (``body_shape``).
LED_BODY_SHAPES = ("sphere", "cylinder")


def _check_wavelengths(value) -> None:
    """Each LED wavelength (one number or a list) a finite number in WAVELENGTH_RANGE_NM;
    ValueError naming the item (``wavelength_nm[k] = …``) and the value otherwise."""
    items = list(enumerate(value)) if isinstance(value, list | tuple) else [(None, value)]
    lo, hi = WAVELENGTH_RANGE_NM
    for k, v in items:
        name = "" if k is None else f"wavelength_nm[{k}] = {v!r}: "  # one value: named outside
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise ValueError(f"{name}must be a finite number of nanometres")
        if v <= 0:
            raise ValueError(f"{name}must be > 0 (nm)")
        if not lo <= v <= hi:
            raise ValueError(f"{name}must lie in {lo:g} … {hi:g} nm")


def _holds_bool(annotation) -> bool:
    """Whether a field's type admits ``bool`` (``bool``, ``bool | None``, …)."""
    return annotation is bool or any(_holds_bool(a) for a in get_args(annotation))


def _only_bool(annotation) -> bool:
    """Whether a field is a switch: ``bool`` or ``bool | None``."""
    return annotation is bool or (
        bool in get_args(annotation) and set(get_args(annotation)) <= {bool, type(None)}
    )


class _Model(BaseModel):
    """Every scene table: unknown keys, NaN and ±inf refused; ``true``/``false`` refused where
    a number is asked (pydantic's lax mode would read ``count = true`` as 1), and a switch
    (a ``bool`` field) takes only ``true`` or ``false`` (lax mode would read 1, 0, "yes")."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _no_bool_for_a_number(cls, v, info):
        items = v if isinstance(v, list | tuple) else [v]
        flat = [x for it in items for x in (it if isinstance(it, list | tuple) else [it])]
        annotation = cls.model_fields[info.field_name].annotation
        if any(isinstance(x, bool) for x in flat) and not _holds_bool(annotation):
            raise ValueError("true/false is not a value this field takes")
        if _only_bool(annotation) and not (isinstance(v, bool) or v is None):
            # pydantic's lax mode would read 1, 0, "yes", "off" as a switch
            raise ValueError("must be true or false (a switch)")
        return v


class LedProfile(_Model):
    """Relative radiant intensity I(α)/I(0) of an LED against the angle α from its axis.

    ``kind = "cos_power"``: I(α)/I(0) = cos^m α with m chosen so that the intensity is half at
    ``half_intensity_angle_deg`` (the datasheet's half of the full spread angle).
    ``kind = "table"``: a CSV file of two columns, angle in degrees (0 … ≤ 90, increasing) and
    relative intensity, linearly interpolated; a path relative to the scene file.
    """

    kind: Literal["cos_power", "table"] = "cos_power"
    half_intensity_angle_deg: float = Field(22.5, gt=0, lt=90)
    table_csv: str | None = None

    @model_validator(mode="after")
    def _table_needs_file(self) -> LedProfile:
        if self.kind == "table" and not self.table_csv:
            raise ValueError("kind 'table' needs table_csv, the path of the profile CSV")
        return self


#: The ring's fields (:class:`LedArray`): refused beside ``positions_mm``, where they place nothing.
RING_FIELDS = (
    "azimuths_deg",
    "height_mm",
    "distance_mm",
    "pitch_deg",
    "ring_centre_mm",
    "ring_axis",
)


class LedArray(_Model):
    """N identical LEDs: a ring (paper Fig. 8) about any axis, or placed one by one.

    The ring: LED ``i`` sits at azimuth φᵢ, its body centre at c + Y (cos φ ê₁ + sin φ ê₂) + Z n̂
    in the world frame, its axis pitched by θ from −n̂ toward the ring's axis. The ring's centre
    c = ``ring_centre_mm`` and axis n̂ = ``ring_axis`` default to the corneal vertex and world +z,
    where ê₁, ê₂ = +x, +y (the paper's ring: (Y cos φ, Y sin φ, Z), φ from +x toward +y as seen
    from the camera); for another axis ê₁ is world +x made perpendicular to n̂ (world +y when n̂
    is along x) and ê₂ = n̂ × ê₁. One by one: ``positions_mm`` (N, 3) body centres (world mm;
    the ring's Y, Z, θ and azimuths are then not used). Aim: ``aim_at_mm``, a point every LED's
    axis points at (instead of the pitch θ), or, for LEDs placed one by one, ``directions``
    (N, 3).
    Per LED: ``radiant_intensity_w_sr`` (on-axis I₀), ``profile``, ``wavelength_nm``,
    ``body_diameter_mm`` and ``emitter_diameter_mm`` are each either one value for every LED or
    a list of ``count`` values, LED k taking item k (in the order of ``positions_mm``, or of the
    ring's azimuths); in TOML a list of profiles is an array of tables, ``[[leds.profile]]`` once
    per LED.
    ``wavelength_nm`` (default: the scene's ``wavelength_nm``) is each LED's own, within the
    scene wavelength's range (:data:`WAVELENGTH_RANGE_NM`): LEDs of several wavelengths are
    rendered as a sum over wavelength groups, each group traced at its own wavelength (indices of
    the eye and the lens, the cornea's Fresnel reflection) with only its LEDs emitting, and each
    LED's eye-safety weight taken at its own wavelength (:func:`eyelume.render.render`,
    :func:`eyelume.compile.wavelength_groups`). ``spectral_width_nm`` is the LEDs' emission
    spectrum's full width at half maximum, 0 to 200 nm (datasheets give about 30–40 nm at 850
    nm, 50 nm at 940 nm): one for every LED, or a list of ``count``, the same for LEDs of the
    same wavelength (a wavelength group is counted as one). The sensor counts each group's light
    over a Gaussian spectrum of that width centred on its wavelength (QE(λ) λ/(hc) averaged over
    it, :func:`eyelume.detectors.sensor.electrons_per_w_mm2`); the tracing, the eye's indices and
    the eye-safety weights stay at the centre wavelength. 0 (the default): a line spectrum. The
    ring's fields (``height_mm``,
    ``distance_mm``, ``pitch_deg``, ``azimuths_deg``, ``ring_centre_mm``, ``ring_axis``) given
    beside ``positions_mm`` are refused (they would place nothing).
    The body (one value for every LED or a list of ``count``, as the numbers above), a closed
    absorber about the LED's centre (``positions_mm`` or the ring's point: the body's centre):
    ``body_shape = "sphere"`` (the default; a 3 or 5 mm dome LED) is a sphere of diameter
    ``body_diameter_mm``, light leaving from its apex, centre + (D/2)·axis;
    ``body_shape = "cylinder"`` (a flat SMD package, top emitter, e.g. a 1.7 × 0.8 × 0.65 mm
    CHIPLED as a cylinder of its footprint's area) is a closed cylinder coaxial with the LED's
    axis, ``body_diameter_mm`` across and ``body_length_mm`` long (along the axis), centred on
    the LED's centre, light leaving from the centre of its front face, centre + (L/2)·axis
    (:meth:`emission_offsets_mm`). ``body_length_mm`` (mm) is needed when an LED is a cylinder;
    a sphere's length is its diameter (in a list, a sphere's item must equal its
    ``body_diameter_mm``). The body absorbs what comes back to it, whichever LEDs emit (the
    ledger's "LED bodies"): it shadows the eye and the face from other LEDs and hides the
    skin behind it from the camera; the checks that refuse an LED inside the eye, the face,
    the lens, the camera body, an element or another LED, or behind the eye plane, take its
    shape (:mod:`eyelume.scene.sources`, :func:`~eyelume.scene.sources.body_points`).
    ``emitter_diameter_mm`` is the apparent size of each LED's emitting area (the die as the dome
    lens shows it), used only for the retinal thermal hazard (its radiance and angular
    subtense): the tracers emit from a point at the emission point above; it must fit within
    the body's diameter.
    """

    part: str = "American Bright BIR-BO07J4Q-1"
    count: int = Field(4, ge=1, le=64)
    azimuths_deg: list[float] | None = None
    height_mm: NonNegative = 30.0
    distance_mm: Positive = 70.0
    pitch_deg: float = Field(20.0, gt=-90, lt=90)
    body_diameter_mm: Positive | list[Positive] = 5.0
    body_shape: Literal["sphere", "cylinder"] | list[Literal["sphere", "cylinder"]] = "sphere"
    body_length_mm: Positive | list[Positive] | None = None
    emitter_diameter_mm: Positive | list[Positive] = 1.0
    radiant_intensity_w_sr: Positive | list[Positive] = 0.015
    profile: LedProfile | list[LedProfile] = LedProfile()
    wavelength_nm: float | list[float] | None = None
    spectral_width_nm: float | list[float] = 0.0
    ring_centre_mm: Vector3 = (0.0, 0.0, 0.0)
    ring_axis: Vector3 = (0.0, 0.0, 1.0)
    positions_mm: list[Vector3] | None = None
    aim_at_mm: Vector3 | None = None
    directions: list[Vector3] | None = None

    @field_validator(*PER_LED_NUMBERS, mode="before")
    @classmethod
    def _numbers_one_by_one(cls, value, info):
        """A list is checked item by item, so a bad item is named by its index; a wavelength,
        one or each, must also lie in :data:`WAVELENGTH_RANGE_NM`."""
        if info.field_name == "wavelength_nm" and value is not None:
            _check_wavelengths(value)
        if isinstance(value, list | tuple):
            if not value:
                raise ValueError(f"{info.field_name} = []: give a number or one per LED")
            for k, v in enumerate(value):
                if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                    raise ValueError(f"{info.field_name}[{k}] = {v!r}: must be a finite number")
                if v <= 0:
                    raise ValueError(f"{info.field_name}[{k}] = {v!r}: must be > 0")
        return value

    @field_validator("body_shape", mode="before")
    @classmethod
    def _shapes_one_by_one(cls, value):
        """Each body shape one of :data:`LED_BODY_SHAPES`, a bad item named by its index."""
        items = list(enumerate(value)) if isinstance(value, list | tuple) else [(None, value)]
        if not items:
            raise ValueError("body_shape = []: give one shape or one per LED")
        for k, v in items:
            if v not in LED_BODY_SHAPES:
                name = "" if k is None else f"body_shape[{k}] = {v!r}: "
                raise ValueError(f"{name}must be one of {', '.join(LED_BODY_SHAPES)}")
        return value

    @model_validator(mode="after")
    def _cylinders_have_a_length(self) -> LedArray:
        """A cylinder needs ``body_length_mm``; a length beside spheres only is refused (it
        would size nothing), and a list's item for a sphere must be its diameter."""
        shapes = self.body_shapes()
        if len(shapes) != self.count:
            return self  # _per_led_lengths names the list's count
        v = self.body_length_mm
        if v is None:
            if "cylinder" in shapes:
                k = shapes.index("cylinder")
                raise ValueError(
                    f"body_length_mm is needed: LED {k}'s body_shape is 'cylinder' (give the "
                    "package's length along the LED's axis, mm)"
                )
            return self
        if "cylinder" not in shapes:
            raise ValueError(
                f"body_length_mm = {v!r} given but every LED's body_shape is 'sphere' (whose "
                "length is its diameter): remove it or set body_shape = 'cylinder'"
            )
        if isinstance(v, list) and len(v) == self.count:
            diameters = self.body_diameter_mm
            for k, (shape, length) in enumerate(zip(shapes, v, strict=True)):
                d = diameters[k] if isinstance(diameters, list) else diameters
                if shape == "sphere" and length != d:
                    raise ValueError(
                        f"body_length_mm[{k}] = {length:g}: LED {k}'s body is a sphere, whose "
                        f"length is its diameter (body_diameter_mm = {d:g}); give {d:g}"
                    )
        return self

    @field_validator("spectral_width_nm", mode="before")
    @classmethod
    def _widths_one_by_one(cls, value):
        """Each width a finite number of 0 to 200 nm, a bad item named by its index."""
        items = list(enumerate(value)) if isinstance(value, list | tuple) else [(None, value)]
        if not items:
            raise ValueError("spectral_width_nm = []: give a number or one per LED")
        for k, v in items:
            name = "" if k is None else f"spectral_width_nm[{k}] = {v!r}: "
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise ValueError(f"{name}must be a finite number (nm)")
            if not 0 <= v <= 200:
                raise ValueError(f"{name}an LED's spectral FWHM lies within 0-200 nm")
        return [float(v) for v in value] if isinstance(value, list | tuple) else float(value)

    @model_validator(mode="after")
    def _one_width_per_wavelength(self) -> LedArray:
        """LEDs of one wavelength form one group, counted over one spectrum: same width."""
        widths = self.spectral_widths_nm()
        if len(widths) != self.count:
            raise ValueError(
                f"spectral_width_nm has {len(widths)} entries but there are {self.count} LEDs "
                "(count): give one value for every LED or one per LED"
            )
        lams = self.wavelengths_nm(0.0)  # the scene's wavelength stands for None: one value
        if len(lams) != self.count:
            return self  # _per_led_lengths names the wavelength list's count
        first: dict[float, int] = {}
        for k, (lam, w) in enumerate(zip(lams, widths, strict=True)):
            j = first.setdefault(lam, k)
            if widths[j] != w:
                raise ValueError(
                    f"spectral_width_nm[{k}] = {w:g} differs from spectral_width_nm[{j}] = "
                    f"{widths[j]:g} of an LED of the same wavelength: LEDs of one wavelength are "
                    "counted over one spectrum, give them one width"
                )
        return self

    def spectral_widths_nm(self) -> list[float]:
        """Every LED's spectral FWHM (nm), ``count`` values (0: a line)."""
        v = self.spectral_width_nm
        return list(v) if isinstance(v, list) else [float(v)] * self.count

    def spectral_width_at(self, wavelength_nm: float, scene_wavelength_nm: float) -> float:
        """The spectral FWHM (nm) of the LEDs shining at ``wavelength_nm`` (0 if none do)."""
        lams = self.wavelengths_nm(scene_wavelength_nm)
        for lam, w in zip(lams, self.spectral_widths_nm(), strict=True):
            if lam == wavelength_nm:
                return w
        return 0.0

    @property
    def has_spectral_width(self) -> bool:
        """Whether any LED has a spectral width (> 0)."""
        return any(w > 0 for w in self.spectral_widths_nm())

    @field_validator("profile", mode="before")
    @classmethod
    def _profiles_one_by_one(cls, value):
        """A list of profiles is checked item by item, so a bad one is named by its index."""
        if isinstance(value, list | tuple):
            if not value:
                raise ValueError("profile = []: give one profile or one per LED")
            out = []
            for k, v in enumerate(value):
                try:
                    out.append(LedProfile.model_validate(v))
                except ValidationError as exc:
                    err = exc.errors()[0]
                    where = ".".join(str(p) for p in err["loc"])
                    what = f"profile[{k}]" + (f".{where}" if where else "")
                    msg = err["msg"].removeprefix("Value error, ")
                    raise ValueError(f"{what} = {err.get('input')!r}: {msg}") from None
            return out
        return value

    @model_validator(mode="after")
    def _per_led_lengths(self) -> LedArray:
        for name in (*PER_LED_NUMBERS, "profile", "body_shape"):
            v = getattr(self, name)
            if isinstance(v, list) and len(v) != self.count:
                raise ValueError(
                    f"{name} has {len(v)} entries but there are {self.count} LEDs (count): give "
                    "one value for every LED or one per LED"
                )
        return self

    @model_validator(mode="before")
    @classmethod
    def _count_from_positions(cls, data):
        """LEDs placed one by one without ``count``: as many as ``positions_mm`` holds (the
        ring's default of 4 made a file of six positions fail with "count is 4")."""
        if isinstance(data, dict) and "count" not in data:
            pos = data.get("positions_mm")
            if isinstance(pos, list | tuple) and pos:
                data = {**data, "count": len(pos)}
        return data

    @model_validator(mode="after")
    def _no_ring_beside_positions(self) -> LedArray:
        if self.positions_mm is None:
            return self
        for name in RING_FIELDS:
            if name in self.model_fields_set:
                raise ValueError(
                    f"{name} = {getattr(self, name)!r} given beside positions_mm: the LEDs are "
                    "placed one by one, so the ring's fields place nothing; remove it"
                )
        return self

    @model_serializer(mode="wrap")
    def _dump_without_unused_ring(self, handler):
        """LEDs placed one by one are written without the ring's fields they do not use (so a
        written scene reads back: those fields are refused beside ``positions_mm``)."""
        data = handler(self)
        if self.positions_mm is not None and isinstance(data, dict):
            for name in RING_FIELDS:
                if name not in self.model_fields_set:
                    data.pop(name, None)
        return data

    @model_validator(mode="after")
    def _emitter_within_body(self) -> LedArray:
        """The emitting area sits inside the LED's package: an emitter wider than the body is a
        unit slip (µm for mm) that would make the retinal hazard look far smaller."""
        for k, (e, b) in enumerate(
            zip(self.emitter_diameters_mm(), self.body_radii_mm(), strict=True)
        ):
            if e > 2 * b:
                item = f"[{k}]" if isinstance(self.emitter_diameter_mm, list) else ""
                raise ValueError(
                    f"emitter_diameter_mm{item} = {e:g} is wider "
                    f"than the LED's body (body_diameter_mm = {2 * b:g}): the emitting area "
                    "lies inside the package (a size in µm given as mm?)"
                )
        return self

    @model_validator(mode="after")
    def _azimuths_match_count(self) -> LedArray:
        ring = self.positions_mm is None
        if ring and self.azimuths_deg is not None and len(self.azimuths_deg) != self.count:
            raise ValueError(
                f"azimuths_deg has {len(self.azimuths_deg)} entries but count is {self.count}"
            )
        if not any(self.ring_axis):
            raise ValueError("ring_axis = (0, 0, 0) has no direction")
        for name in ("positions_mm", "directions"):
            v = getattr(self, name)
            if v is not None and len(v) != self.count:
                raise ValueError(f"{name} has {len(v)} entries but count is {self.count}")
        return self

    @model_validator(mode="after")
    def _placement_consistent(self) -> LedArray:
        if self.directions is not None:
            if self.positions_mm is None:
                raise ValueError("directions needs positions_mm (LEDs placed one by one)")
            if self.aim_at_mm is not None:
                raise ValueError("give aim_at_mm or directions, not both")
            for k, d in enumerate(self.directions):
                if not any(d):
                    raise ValueError(f"directions[{k}] = (0, 0, 0) has no direction")
        if self.positions_mm is not None and self.directions is None and self.aim_at_mm is None:
            raise ValueError("LEDs placed by positions_mm need aim_at_mm or directions")
        return self

    @model_validator(mode="after")
    def _aim_not_at_an_led(self) -> LedArray:
        for k, c in enumerate(self.positions_mm or []):
            if self.aim_at_mm is not None and tuple(c) == tuple(self.aim_at_mm):
                raise ValueError(f"aim_at_mm equals positions_mm[{k}]: no direction")
        return self

    def intensities_w_sr(self) -> list[float]:
        """On-axis radiant intensity I₀ of every LED (W/sr), ``count`` values."""
        v = self.radiant_intensity_w_sr
        return [float(x) for x in v] if isinstance(v, list) else [float(v)] * self.count

    def body_radii_mm(self) -> list[float]:
        """The radius of every LED's body (mm), ``count`` values: half its
        ``body_diameter_mm`` (a sphere's radius, a cylinder's across its axis)."""
        v = self.body_diameter_mm
        return [x / 2 for x in v] if isinstance(v, list) else [v / 2] * self.count

    def body_shapes(self) -> list[str]:
        """Every LED's body shape (``"sphere"`` or ``"cylinder"``), ``count`` values."""
        v = self.body_shape
        return list(v) if isinstance(v, list) else [v] * self.count

    def body_lengths_mm(self) -> list[float]:
        """Every LED body's length along its axis (mm), ``count`` values: a cylinder's
        ``body_length_mm``, a sphere's diameter."""
        v = self.body_length_mm
        lengths = [float(x) for x in v] if isinstance(v, list) else [v] * self.count
        return [
            2 * r if shape == "sphere" else float(length)
            for shape, r, length in zip(
                self.body_shapes(), self.body_radii_mm(), lengths, strict=True
            )
        ]

    def emission_offsets_mm(self) -> list[float]:
        """Every LED's emission point's distance from its body's centre along its axis (mm),
        ``count`` values: the light leaves from centre + offset · axis, a sphere's apex (its
        radius) or the centre of a cylinder's front face (half its length)."""
        return [
            r if shape == "sphere" else length / 2
            for shape, r, length in zip(
                self.body_shapes(), self.body_radii_mm(), self.body_lengths_mm(), strict=True
            )
        ]

    def bounding_radii_mm(self) -> list[float]:
        """Every LED body's bounding sphere's radius about its centre (mm): a sphere's radius,
        a cylinder's √(r² + (L/2)²)."""
        return [
            r if shape == "sphere" else math.hypot(r, length / 2)
            for shape, r, length in zip(
                self.body_shapes(), self.body_radii_mm(), self.body_lengths_mm(), strict=True
            )
        ]

    def emitter_diameters_mm(self) -> list[float]:
        """The apparent diameter of every LED's emitting area (mm), ``count`` values."""
        v = self.emitter_diameter_mm
        return [float(x) for x in v] if isinstance(v, list) else [float(v)] * self.count

    def profiles(self) -> list[LedProfile]:
        """The angular profile of every LED, ``count`` profiles."""
        v = self.profile
        return list(v) if isinstance(v, list) else [v] * self.count

    def wavelengths_nm(self, scene_wavelength_nm: float) -> list[float]:
        """The wavelength of every LED (nm), ``count`` values; the scene's where not given."""
        v = self.wavelength_nm
        if v is None:
            return [float(scene_wavelength_nm)] * self.count
        return [float(x) for x in v] if isinstance(v, list) else [float(v)] * self.count

    @property
    def all_alike(self) -> bool:
        """True when every LED has the same I₀ and profile (one value given for all, or a list
        of equal ones)."""
        return len(set(self.intensities_w_sr())) == 1 and all(
            p == self.profiles()[0] for p in self.profiles()
        )

    @property
    def is_paper_ring(self) -> bool:
        """True for the paper's ring: about world z through the vertex, pitched by θ."""
        return (
            self.positions_mm is None
            and self.aim_at_mm is None
            and tuple(self.ring_centre_mm) == (0.0, 0.0, 0.0)
            and tuple(self.ring_axis) == (0.0, 0.0, 1.0)
        )

    def azimuths(self) -> list[float]:
        """Azimuth of every LED in degrees (evenly spaced from 0° unless given; of LEDs placed
        one by one, their positions' about the world z axis)."""
        if self.positions_mm is not None:
            return [math.degrees(math.atan2(p[1], p[0])) % 360.0 for p in self.positions_mm]
        if self.azimuths_deg is not None:
            return list(self.azimuths_deg)
        return [360.0 * i / self.count for i in range(self.count)]


class EyeSurface(_Model):
    """One row of a schematic-eye prescription (eye frame, lens-design sign convention).

    The medium *after* the surface (toward the retina; the last row, the retina, has none) is
    given as the eye's ``dispersion`` needs it (:class:`Eye`): ``nd, nF, nC``, its indices at
    the d (587.56 nm), F (486.13 nm) and C (656.27 nm) lines (``"cauchy_dFC"``); or ``medium``
    (cornea, aqueous, lens, vitreous) and ``n_ref``, its index at the eye's
    ``reference_wavelength_nm`` (``"atchison_smith_2005"``).
    """

    name: str
    radius_mm: Radius
    conic: float = 0.0
    thickness_mm: NonNegative = 0.0
    semi_diameter_mm: Positive
    nd: float | None = Field(None, gt=1)
    nF: float | None = Field(None, gt=1)
    nC: float | None = Field(None, gt=1)
    medium: Literal["cornea", "aqueous", "lens", "vitreous"] | None = None
    n_ref: float | None = Field(None, gt=1, lt=2)

    @model_validator(mode="after")
    def _finite_radius(self) -> EyeSurface:
        if self.radius_mm == 0:
            raise ValueError("radius_mm is 0: use inf for a flat surface")
        return self


class ContactLens(_Model):
    """A contact lens on the eye (issue 14): a thin shell of ``thickness_mm`` concentric with
    the anterior cornea, its front of index ``refractive_index`` over the tear film.

    Defaults: n = 1.50 — the issue's figure; rigid lenses are 1.44–1.51 (PMMA 1.49; rigid
    gas-permeable materials lower), soft hydrogels 1.37–1.44 (lower the more water they hold),
    the ranges contact-lens texts give; ASSUMPTION for any one lens — and 0.10 mm (ASSUMPTION:
    a −3 D soft lens is ~0.07–0.12 mm thick at its centre, a rigid one ~0.12–0.2). How it is
    applied: :func:`eyelume.scene.eye.with_contact_lens`.
    """

    refractive_index: float = Field(1.50, gt=1.0, le=2.0)
    thickness_mm: float = Field(0.10, gt=0.0, le=1.0)


class AnteriorCornea(_Model):
    """The anterior cornea's astigmatism and its placement on the eye (issue 15).

    Shape: the *general ellipsoid* of Navarro, González & Hernández-Matamoros, "On the
    prediction of optical aberrations by personalized eye models", Optom. Vis. Sci. 83:371
    (2006): in the surface's own frame (apex at the origin, z into the eye, x along the flat
    meridian) the quadric

        x²/R_flat + y²/R_steep + (1 + Q) z²/R_flat − 2 z = 0,

    whose apical radii are R_flat = ``eye.surfaces.0.radius_mm`` along the flat meridian and
    R_steep = ``radius_steep_mm`` along the steep one, and whose meridional asphericities are
    Q_flat = ``eye.surfaces.0.conic`` and Q_steep = (1 + Q_flat) R_steep / R_flat − 1 (a
    quadric has one z² coefficient: the two Q are not independent; for 1 D of corneal
    astigmatism they differ by ~0.02). With ``radius_steep_mm`` unset (or equal to R_flat) it
    is the rotationally symmetric conicoid of ``eye.surfaces.0``.

    ``axis_deg``: the flat meridian's axis in the optometric TABO convention (degrees
    0–180, counter-clockwise from the examiner's right, i.e. from world +x toward +y, as seen
    facing the eye), for the eye as the file is written (a right eye). A left eye
    (``eye_pose.which = "left"``) mirrors the whole scene, so its axis is 180° − ``axis_deg``:
    fellow eyes' astigmatism is mostly mirror-symmetric (enantiomorphic; Hashemi et al.,
    J. Optom. 12:44, 2019). With-the-rule corneal astigmatism (steep vertical) is
    ``axis_deg`` ≈ 0 or 180; against-the-rule ≈ 90.

    ``decentration_mm``: the anterior cornea's apex offset (x, y) from the eye's optical axis
    (x toward the nose of the right eye as written, y up), mm; ``tilt_deg``: its axis tilted
    (vertical: toward +y; horizontal: toward +x) about the apex, degrees. The posterior cornea,
    iris, lens and sclera stay on the optical axis. Typical values: the corneal apex lies a few
    tenths of a mm from the pupil centre and the corneal topographic axis a few degrees from the
    pupillary axis (Mandell, Chiang & Klein, "Location of the major corneal reference points",
    Optom. Vis. Sci. 72:776, 1995; magnitudes quoted from memory, ASSUMPTION). Refused
    (:func:`eyelume.scene.eye.check_eye_geometry`): a cornea whose edge no longer meets the
    sclera within 1 mm (ASSUMPTION: within the limbus, a band 1–2 mm wide), reaches
    the iris plane or crosses the posterior cornea.
    """

    radius_steep_mm: float | None = Field(None, gt=0.0, le=MAX_MAGNITUDE)
    axis_deg: float = Field(0.0, ge=0.0, le=180.0)
    decentration_mm: tuple[
        Annotated[float, Field(ge=-2.0, le=2.0)], Annotated[float, Field(ge=-2.0, le=2.0)]
    ] = (0.0, 0.0)
    tilt_deg: tuple[
        Annotated[float, Field(ge=-15.0, le=15.0)], Annotated[float, Field(ge=-15.0, le=15.0)]
    ] = (0.0, 0.0)

    @property
    def placed(self) -> bool:
        """Whether the apex is decentred or its axis tilted."""
        return any(self.decentration_mm) or any(self.tilt_deg)


class Eye(_Model):
    """A schematic eye with its Lambertian tissues.

    ``surfaces`` are the refracting surfaces followed by the retina, in order from the anterior
    cornea. The iris is a Lambertian annulus in the vertex plane of surface ``iris_surface`` (the
    anterior lens, where the Arizona eye has its pupil); the sclera a
    Lambertian sphere of ``sclera_radius_mm`` through the corneal limbus (the edge of the anterior
    cornea's clear aperture); its inner face and the retina reflect ``retina_reflectance``. The
    iris root, an annulus from the iris's outer edge to the sclera in the iris's plane with the
    iris's reflectance, closes the eye: light enters it only through the pupil.

    Gaze: the eye turns about its centre of rotation, ``rotation_centre_mm`` behind the anterior
    corneal vertex of primary gaze, first by ``gaze_vertical_deg`` about the x axis (positive:
    looking up, +y), then by ``gaze_horizontal_deg`` about the y axis (positive: looking toward
    +x, the nose of a right eye). The world frame stays that of primary gaze (ARCHITECTURE.md §2).
    The gaze angles are the optical axis's (the schematic eye's axis of symmetry).

    ``kappa_deg``: the angle kappa, (horizontal, vertical) degrees: the visual axis (the line of
    sight to what the eye fixates) is the eye-frame direction at these angles from the optical
    axis (positive horizontal: nasal, toward +x of a right eye; positive vertical: up), turned
    with the gaze — ``eyelume.analysis.truth.visual_axis``. Default (0, 0): the schematic eyes
    of the library are rotationally symmetric, their visual and optical axes one; real eyes
    have about +5° ± 2° horizontally (Atchison & Smith, Optics of the Human Eye, 2000, ch. 4;
    ``scene/presets/eyes/population.toml`` samples it). The render does not change with it; it
    tells where the person looks: truth.json's ``visual_axis`` and the tracking evaluation,
    whose grid gazes are fixation targets of the visual axis
    (:func:`eyelume.optimize.tracking.render_frame`). Each component within ±15°.

    ``contact_lens``: a contact lens on the cornea (:class:`ContactLens`; unset: none).

    ``cornea``: the anterior cornea's astigmatism (a second radius and its axis), decentration
    and tilt (:class:`AnteriorCornea`; default: rotationally symmetric, on the axis).

    ``model``: with no ``surfaces`` written, the schematic eye of that name in the library
    (:func:`eyelume.scene.eye_models.eye_model_names`: ``arizona``, ``navarro1999``,
    ``legrand1980``; their data and sources in ``scene/presets/eyes/eye_models.toml``) supplies
    ``surfaces``, ``iris_surface`` (its pupil), ``dispersion`` and ``reference_wavelength_nm``;
    with ``surfaces`` written, those are used as written and ``model`` only names them.

    ``dispersion``: how the media's indices follow the wavelength. ``"cauchy_dFC"``: the
    two-term Cauchy law through each medium's nd, nF, nC (:func:`eyelume.scene.eye.eye_index`;
    extrapolated beyond the visible, as the paper does). ``"atchison_smith_2005"``: Atchison &
    Smith's NIR fits (:func:`eyelume.scene.eye_models.ocular_index`), valid 400–1060 nm; a
    scene wavelength outside is refused.

    ``cornea_reflection``: ``"fixed"``: the glint takes ``cornea_reflectance`` (the paper's
    2.4 %); ``"fresnel"``: Fresnel's R(θ) at the air–cornea step (the cornea's index);
    ``"tear_film"``: Fresnel's normal-incidence reflectance of the tear film at the scene's
    wavelength (:func:`eyelume.scene.eye_models.tear_film_reflectance`, ~2.0 % at 850 nm), as
    a fixed split (its rise with the angle ignored, as for a contact lens).
    """

    model: str = "arizona"
    surfaces: list[EyeSurface]
    dispersion: Literal["cauchy_dFC", "atchison_smith_2005"] = "cauchy_dFC"
    reference_wavelength_nm: float = Field(589.3, ge=400.0, le=1060.0)
    cornea_reflection: Literal["fixed", "fresnel", "tear_film"] = "fixed"
    cornea_reflectance: Fraction = 0.024
    cornea_absorptance: Fraction = 0.0
    iris_surface: int = Field(2, ge=1)
    iris_outer_diameter_mm: Positive = 11.0
    pupil_diameter_mm: Positive = 7.0
    iris_reflectance: Fraction = 0.05
    sclera_radius_mm: Positive = 12.0
    sclera_reflectance: Fraction = 0.09
    retina_reflectance: Fraction = 0.0
    gaze_horizontal_deg: float = Field(0.0, ge=-30.0, le=30.0)
    gaze_vertical_deg: float = Field(0.0, ge=-30.0, le=30.0)
    rotation_centre_mm: Positive = 13.5
    kappa_deg: tuple[float, float] = (0.0, 0.0)
    contact_lens: ContactLens | None = None
    cornea: AnteriorCornea = AnteriorCornea()

    @field_validator("kappa_deg")
    @classmethod
    def _kappa_range(cls, v: tuple[float, float]) -> tuple[float, float]:
        if not all(math.isfinite(k) and abs(k) <= 15.0 for k in v):
            raise ValueError(f"kappa_deg = {list(v)!r}: each angle must lie in ±15°")
        return v

    @model_validator(mode="before")
    @classmethod
    def _from_library(cls, data: Any) -> Any:
        """No ``surfaces`` written: take them (and the pupil's surface, the dispersion law and
        its reference wavelength, unless written) from the library eye ``model``."""
        if not isinstance(data, dict) or "surfaces" in data:
            return data
        name = data.get("model", "arizona")
        if name not in eye_model_names():
            raise ValueError(
                f"model = {name!r} is not an eye model of the library "
                f"({', '.join(eye_model_names())}); or write the eye's [[eye.surfaces]]"
            )
        return {**eye_model_data(name), **data}

    @model_validator(mode="after")
    def _consistent(self) -> Eye:
        if len(self.surfaces) < 3:
            raise ValueError(
                "surfaces needs at least an anterior cornea, one more surface and the retina"
            )
        for j, s in enumerate(self.surfaces[:-1]):
            if self.dispersion == "cauchy_dFC" and None in (s.nd, s.nF, s.nC):
                raise ValueError(f"surface '{s.name}' needs nd, nF and nC of the medium after it")
            if self.dispersion == "atchison_smith_2005" and None in (s.medium, s.n_ref):
                raise ValueError(
                    f"surfaces.{j} ('{s.name}'): dispersion = 'atchison_smith_2005' needs the "
                    "medium after it (cornea, aqueous, lens, vitreous) and its n_ref"
                )
        if self.pupil_diameter_mm >= self.iris_outer_diameter_mm:
            raise ValueError(
                f"pupil_diameter_mm = {self.pupil_diameter_mm} must be smaller than "
                f"iris_outer_diameter_mm = {self.iris_outer_diameter_mm}"
            )
        if self.iris_surface >= len(self.surfaces) - 1:
            raise ValueError(
                f"iris_surface = {self.iris_surface} must index a refracting surface "
                f"(1 … {len(self.surfaces) - 2})"
            )
        if self.cornea_reflectance + self.cornea_absorptance > 1:
            raise ValueError(
                f"cornea_reflectance + cornea_absorptance = "
                f"{self.cornea_reflectance + self.cornea_absorptance} exceeds 1"
            )
        limbus = self.surfaces[0].semi_diameter_mm
        if self.iris_outer_diameter_mm / 2 >= limbus:
            raise ValueError(
                f"iris_outer_diameter_mm = {self.iris_outer_diameter_mm} must fit inside the "
                f"cornea (anterior cornea semi_diameter_mm = {limbus})"
            )
        if self.sclera_radius_mm <= limbus:
            raise ValueError(
                f"sclera_radius_mm = {self.sclera_radius_mm} must exceed the limbus radius {limbus}"
            )
        return self

    @model_validator(mode="after")
    def _steep_meridian(self) -> Eye:
        steep = self.cornea.radius_steep_mm
        if steep is not None and steep > self.surfaces[0].radius_mm:
            raise ValueError(
                f"cornea.radius_steep_mm = {steep} exceeds the flat meridian's radius "
                f"eye.surfaces.0.radius_mm = {self.surfaces[0].radius_mm}: the steep meridian "
                "has the smaller radius (swap them and turn axis_deg by 90)"
            )
        return self


_Offset = Annotated[float, Field(ge=-200.0, le=200.0)]


class EyePose(_Model):
    """Where the eye sits in the headset (the world frame), and which eye it is.

    ``relief_mm``: the eye relief, from the anterior corneal vertex (primary gaze) to the
    headset's reference plane z = 0 along the headset's z axis: the vertex sits at
    z = −``relief_mm`` (0, the default: the reference plane touches the cornea, the frame of
    ``paper2005`` and of every preset written before the eye had a pose).
    ``lateral_offset_mm``: the vertex's (x, y) in the headset frame (0, 0: on its z axis).
    The eye, its face and its eye-plane receiver move with this pose; gaze turns the eye about
    its centre of rotation there, and ``head_offset_mm`` (slip) adds to it for the eye and face
    (the eye plane stays where the pose puts it).

    ``which``: a scene file is written for a **right** eye, +x toward its nose. ``"left"``
    mirrors the whole scene as written about the headset's sagittal plane x = 0 (every
    position, direction, ring, face tissue, offset and the camera's roll: x → −x), which is how
    a headset's left eye station mirrors its right one; so the same file describes either eye,
    nasal stays nasal (the presets' "nasal-below" camera), a positive horizontal gaze is toward
    the nose for both eyes, and everything reported in world coordinates (truth, layout,
    ``eyelume info``) is in the mirrored, physical headset frame. The schematic eye is
    rotationally symmetric but for its cornea's astigmatism axis and placement
    (:class:`AnteriorCornea`), which the mirror carries with the rest.
    """

    which: Literal["right", "left"] = "right"
    relief_mm: float = Field(0.0, ge=-200.0, le=200.0)
    lateral_offset_mm: tuple[_Offset, _Offset] = (0.0, 0.0)

    @property
    def vertex_mm(self) -> Vector3:
        """The anterior corneal vertex in primary gaze without slip, as the file writes it
        (before a left eye's mirror): (x, y, −relief) mm."""
        x, y = self.lateral_offset_mm
        return (x, y, -self.relief_mm)


class Tissue(_Model):
    """A Lambertian face or eyelid structure built from a sphere, cylinder or disk.

    Frame: the shape's local z axis is ``axis`` (world, normalised on use) through ``center_mm``.
    Sphere: radius about the centre. Cylinder: radius about the axis. Disk: the plane through the
    centre normal to the axis. The surface exists where local z ∈ ``clip_z_mm`` and the distance
    from the axis ∈ ``clip_r_mm`` (local frame). ``reflectance`` defaults to the face's skin.
    A tissue reflects on its outer face only (outside a sphere or cylinder, the +axis side of a
    disk) and absorbs on the other: point a disk's axis toward the light.
    ``follows_gaze`` (0–1) is the share of the eye's vertical rotation the tissue takes, turning
    about the eye's centre of rotation about the x axis: an eyelid's lid–eye coordination.
    """

    name: str
    anatomy: str = ""
    shape: Literal["sphere", "cylinder", "disk"]
    center_mm: Vector3
    axis: Vector3 = (0.0, 0.0, 1.0)
    radius_mm: NonNegative = 0.0
    clip_z_mm: tuple[float, float] = (-1.0e6, 1.0e6)
    clip_r_mm: tuple[float, float] = (0.0, 1.0e6)
    reflectance: Fraction | None = None
    follows_gaze: float = Field(0.0, ge=0.0, le=1.0)

    @model_validator(mode="after")
    def _shape_ok(self) -> Tissue:
        if self.shape != "disk" and self.radius_mm <= 0:
            raise ValueError(f"radius_mm = {self.radius_mm} must be > 0 for a {self.shape}")
        if sum(a * a for a in self.axis) == 0:
            raise ValueError("axis = (0, 0, 0) has no direction")
        if self.clip_z_mm[0] >= self.clip_z_mm[1] or self.clip_r_mm[0] >= self.clip_r_mm[1]:
            raise ValueError(
                f"empty clip range clip_z_mm={self.clip_z_mm} clip_r_mm={self.clip_r_mm}"
            )
        return self


class Lashes(_Model):
    """Eyelashes: a deterministic fringe of thin opaque strands along a lid's margin.

    The lid is the face tissue named ``lid`` (a sphere: its margin is the circle where it is
    clipped, local z = ``clip_z_mm[0]`` along its axis, at the distance ρ_m = √(R² − z_m²) from
    the axis). ``count`` straight lashes of ``length_mm`` leave that circle at evenly spaced
    azimuths over ``span_deg`` centred on the forward direction (the world +z, across the lid's
    axis), each pointing away from the axis and ``tilt_deg`` above the plane normal to it (for
    an upper lid, axis +y: above the horizontal). Together they lie on one cone about the lid's
    axis (``kernels/geometry.py``, ``SHAPE_LASHES``); each lash is a ribbon ``width_mm`` wide
    across it, a Lambertian reflector of ``reflectance`` on both faces; light between the
    lashes goes on. They follow the lid's share of the gaze (``follows_gaze``).

    Values (mm, degrees): an adult upper lid carries about 90–160 lashes, 8–12 mm long,
    ~0.1 mm thick (Thibaut et al., "Human eyelash characterization", Br. J. Dermatol. 162:304
    (2010); Na et al. 2006 for the count: ranges as cited, not re-checked here): count 100,
    length 9 mm, width 0.1 mm. ASSUMPTIONS: the curl is replaced by a straight chord 40° above
    the horizontal (lashes leave the lid forward and curl up); the lashes span the central 120°
    of the margin circle (about 25 mm of the lid's ~30 mm, the medial end bare); one row (real
    lashes stand in 2–6 rows); dark hair reflects about 5 % in the near infrared (no measured
    value found; dark hair is strongly absorbing from melanin). Off by default: the paper's
    scene and the presets stay as they were.
    """

    enabled: bool = False
    lid: str = "upper eyelid"
    count: int = Field(100, ge=1, le=1000)
    length_mm: float = Field(9.0, gt=0, le=50.0)
    width_mm: float = Field(0.1, gt=0, le=2.0)
    tilt_deg: float = Field(40.0, ge=5.0, le=85.0)
    span_deg: float = Field(120.0, gt=0, le=180.0)
    reflectance: Fraction = 0.05


class Face(_Model):
    """The face around the eye: eyelids, brow, cheek, nose and periorbital skin, and the
    eyelashes along a lid (:class:`Lashes`, off by default)."""

    enabled: bool = True
    skin_reflectance: Fraction = 0.12
    tissues: list[Tissue] = []
    lashes: Lashes = Lashes()

    @model_validator(mode="after")
    def _lashes_fit(self) -> Face:
        lashes = self.lashes
        if not lashes.enabled:
            return self
        lids = [t for t in self.tissues if t.name == lashes.lid]
        if not lids:
            raise ValueError(
                f"lashes.lid = {lashes.lid!r} names no face tissue "
                f"(tissues: {', '.join(t.name for t in self.tissues) or 'none'})"
            )
        lid = lids[0]
        if lid.shape != "sphere":
            raise ValueError(f"lashes.lid = {lashes.lid!r} is a {lid.shape}: lashes need a sphere")
        z_m = lid.clip_z_mm[0]
        if not -lid.radius_mm < z_m < lid.radius_mm:
            raise ValueError(
                f"lashes.lid = {lashes.lid!r}: its clip_z_mm[0] = {z_m} does not cut its sphere "
                f"(radius {lid.radius_mm} mm): it has no margin for lashes"
            )
        rho = math.sqrt(lid.radius_mm**2 - z_m**2)
        tilt = math.radians(lashes.tilt_deg)
        if rho * math.cos(tilt) + z_m * math.sin(tilt) <= 0:
            raise ValueError(
                f"lashes.tilt_deg = {lashes.tilt_deg}: the lashes would point into the lid"
            )
        pitch = rho * math.radians(lashes.span_deg) / lashes.count
        if lashes.width_mm >= pitch:
            raise ValueError(
                f"lashes.count = {lashes.count} with width_mm = {lashes.width_mm}: the lashes "
                f"overlap at the margin (spacing {pitch:.3g} mm): fewer or thinner lashes"
            )
        return self


class LensSurface(_Model):
    """One surface of the imaging lens prescription (light travels +z, lens-design signs).

    ``glass`` names the medium after the surface in the glass catalogs (empty = air);
    ``paper_glass`` records the name in the source prescription when a substitute is used.
    ``semi_diameter_mm`` unset: sized from a real-ray trace of the full field (see compile).
    """

    radius_mm: Radius = math.inf
    conic: float = 0.0
    thickness_mm: NonNegative
    glass: str = ""
    paper_glass: str = ""
    semi_diameter_mm: Positive | None = None
    stop: bool = False

    @model_validator(mode="after")
    def _finite_radius(self) -> LensSurface:
        if self.radius_mm == 0:
            raise ValueError("radius_mm is 0: use inf for a flat surface")
        return self


class ImagingLens(_Model):
    """The camera lens: object (eye plane) distance, prescription and stop sizing.

    The last surface's ``thickness_mm`` is the distance to the image plane. The stop's
    semi-diameter is sized so that EFL / entrance-pupil diameter = ``f_number`` (infinite
    conjugate, the reading of the paper's "F-number of 2.51").
    """

    name: str = ""
    object_distance_mm: Positive = 70.0
    f_number: Positive = 2.51
    glass_catalogs: list[str] = []
    surfaces: list[LensSurface]

    @model_validator(mode="after")
    def _one_stop(self) -> ImagingLens:
        stops = [i for i, s in enumerate(self.surfaces) if s.stop]
        if len(stops) != 1:
            raise ValueError(f"exactly one surface must have stop = true (found {len(stops)})")
        if self.surfaces[-1].thickness_mm <= 0:
            raise ValueError("the last surface's thickness_mm (distance to the image) must be > 0")
        return self


class IdealLens(_Model):
    """A camera module's lens as its datasheet gives it: a thin, perfect (ideal) lens.

    ``efl_mm`` f, ``f_number`` N = f / D (D the entrance pupil's diameter; the stop is the lens),
    ``focus_distance_mm`` s: the distance from the lens to the plane in focus, so the sensor sits
    at v = 1 / (1/f − 1/s) behind the lens (s > f). Every ray from a point of the focus plane
    meets at its image: a ray crossing the lens plane at height h with slope s⃗ = (dx, dy)/dz
    leaves with slope D(s⃗) − h⃗/f (Zemax's paraxial surface; pbrt's thin-lens camera), where
    D(s⃗) = s⃗ (1 + k1 |s⃗|² + k2 |s⃗|⁴) is the radial distortion of OpenCV's camera model in
    normalised image coordinates (k1 = k2 = 0: none). Depth of field, the blur of a glint off
    the focus plane and the cos⁴ fall-off follow from the geometry; radiance is carried through
    the lens with the étendue of this mapping (see :mod:`eyelume.estimators.camera`).
    """

    efl_mm: float = Field(gt=0.05, le=1000.0)
    f_number: float = Field(gt=0.5, le=64.0)
    focus_distance_mm: Positive
    k1: float = Field(0.0, ge=-1.0, le=1.0)
    k2: float = Field(0.0, ge=-1.0, le=1.0)

    @model_validator(mode="after")
    def _real_image(self) -> IdealLens:
        if self.focus_distance_mm <= self.efl_mm:
            raise ValueError(
                f"focus_distance_mm = {self.focus_distance_mm} must exceed efl_mm = "
                f"{self.efl_mm}: a plane inside the focal length has no real image"
            )
        return self

    @property
    def image_distance_mm(self) -> float:
        """v = 1 / (1/f − 1/s): lens → sensor (mm)."""
        return 1.0 / (1.0 / self.efl_mm - 1.0 / self.focus_distance_mm)

    @property
    def pupil_radius_mm(self) -> float:
        """D / 2 = f / (2N): the entrance (and exit) pupil's radius, the lens's aperture (mm)."""
        return self.efl_mm / (2.0 * self.f_number)


class CameraBody(_Model):
    """The camera's body: a closed, absorbing cylinder coaxial with the lens, its front face in
    the plane of the lens's first vertex (an ideal lens: the lens, its entrance pupil) with the
    lens's clear aperture as its only opening, reaching ``length_mm`` behind it (away from the
    scene). It shadows light in both estimators (the ledger's "camera body") and no LED may
    sit inside it.

    ``enabled``: unset, an ideal (module) lens has its body and a prescription lens none (the
    paper's rig models the lens mount only); ``true`` or ``false`` decides. Default size: 6 mm
    across, 5 mm deep — ASSUMPTION: an OV6211/OV7251-class board camera with an M6-or-smaller
    lens barrel (such modules are 5–8 mm); replace with your module's.
    """

    enabled: bool | None = None
    diameter_mm: float = Field(6.0, gt=0.0, le=1000.0)
    length_mm: float = Field(5.0, gt=0.0, le=1000.0)


class Camera(_Model):
    """The camera's optics and where it is and looks, in the world (headset) frame (mm, °).

    ``optics``: ``"prescription"``, the sequential lens of ``[lens]``, or ``"ideal"``, the thin
    lens of a module datasheet in ``[camera.ideal]`` (:class:`IdealLens`).

    ``position_mm``: the lens's position (the first vertex of the prescription); unset, the
    camera sits on the world z axis at ``lens.object_distance_mm`` (the paper's rig).
    The view: ``look_at_mm`` (a point the lens looks at) or ``direction`` (a vector from the
    lens toward the scene); unset, the camera looks along −z. ``roll_deg`` turns the camera
    about its viewing axis (right-handed about the axis from the scene to the camera: a positive
    roll turns the camera's right axis toward its up axis). The transform and its conventions are in
    :mod:`eyelume.scene.pose`: everything is traced in the camera's frame, whose z axis is the
    lens axis. ``body``: the camera's body behind the lens (:class:`CameraBody`; an ideal lens
    has a default one).

    ``psf``: the point-spread function convolved with the traced (geometric) image-plane
    irradiance before the sensor's electronics (:mod:`eyelume.detectors.psf`):
    ``"diffraction"``, the Airy pattern of the circular pupil at the scene's wavelength and the
    camera's working F-number, integrated over the pixels; ``"none"``, the geometric image as
    traced. Unset: ``"diffraction"`` for an ideal lens (a module whose 3 µm pixels are about
    one Airy radius: a geometric glint would be one pixel, which no real camera records) and
    ``"none"`` for a prescription (its trace carries the aberrations, not diffraction; the
    paper's 530 µm picture bins are ~100 Airy radii, and its render stays bit-identical).
    """

    optics: Literal["prescription", "ideal"] = "prescription"
    ideal: IdealLens | None = None
    psf: Literal["diffraction", "none"] | None = None
    position_mm: Vector3 | None = None
    look_at_mm: Vector3 | None = None
    direction: Vector3 | None = None
    roll_deg: float = Field(0.0, ge=-180.0, le=180.0)
    body: CameraBody = CameraBody()

    @property
    def body_used(self) -> CameraBody | None:
        """The camera's body, or None: ``body.enabled``, unset, is true for an ideal lens and
        false for a prescription (:class:`CameraBody`)."""
        enabled = self.body.enabled
        if enabled is None:
            enabled = self.optics == "ideal"
        return self.body if enabled else None

    @property
    def psf_used(self) -> str:
        """The point-spread function applied: ``psf``, unset → ``"diffraction"`` for an ideal
        lens, ``"none"`` for a prescription."""
        if self.psf is not None:
            return self.psf
        return "diffraction" if self.optics == "ideal" else "none"

    @model_validator(mode="after")
    def _one_view(self) -> Camera:
        if self.optics == "ideal" and self.ideal is None:
            raise ValueError("optics = 'ideal' needs [camera.ideal] (efl_mm, f_number, …)")
        if self.look_at_mm is not None and self.direction is not None:
            raise ValueError("give look_at_mm or direction, not both")
        if self.direction is not None and not any(self.direction):
            raise ValueError("direction = (0, 0, 0) has no direction")
        if self.look_at_mm is not None and self.position_mm is not None:
            if tuple(self.look_at_mm) == tuple(self.position_mm):
                raise ValueError(
                    f"look_at_mm = {list(self.look_at_mm)} equals position_mm: no direction"
                )
        return self

    def pose(self, object_distance_mm: float) -> tuple[Vector3, Vector3]:
        """(position, viewing direction) in the world frame, the defaults filled in."""
        pos = self.position_mm or (0.0, 0.0, float(object_distance_mm))
        if self.direction is not None:
            return pos, self.direction
        if self.look_at_mm is None:
            return pos, (0.0, 0.0, -1.0)
        view = tuple(t - p for t, p in zip(self.look_at_mm, pos, strict=True))
        if not any(view):
            raise ValueError(f"look_at_mm = {list(self.look_at_mm)} equals the camera position")
        return pos, view  # type: ignore[return-value]


class SensorFilter(_Model):
    """An optical filter in front of the sensor: its transmittance T(λ) multiplies the sensor's
    spectral response to every light, the LEDs' and the sun's
    (:func:`eyelume.detectors.sensor.spectral_response_nm`).

    ``kind``:

    * ``"long_pass"``: T = ``transmittance`` for λ ≥ ``cut_on_nm``, 0 below;
    * ``"band_pass"``: T = ``transmittance`` for ``cut_on_nm`` ≤ λ ≤ ``cut_off_nm``, 0 outside;
    * ``"table"``: T(λ) from the CSV file ``table_csv`` (two columns ``wavelength_nm,
      transmittance``, wavelengths increasing, T in [0, 1]; relative to the scene file),
      linearly interpolated. An LED spectrum must lie within the table; for sunlight the
      filter blocks outside the table's rows.

    The long- and band-pass edges are ideal steps (an idealisation: a real interference filter's
    edge spans 10–30 nm and shifts with the angle of incidence; give a table for a real one).
    """

    kind: Literal["long_pass", "band_pass", "table"]
    cut_on_nm: float | None = Field(None, ge=WAVELENGTH_RANGE_NM[0], le=WAVELENGTH_RANGE_NM[1])
    cut_off_nm: float | None = Field(None, ge=WAVELENGTH_RANGE_NM[0], le=WAVELENGTH_RANGE_NM[1])
    transmittance: float = Field(1.0, gt=0.0, le=1.0)
    table_csv: str | None = None

    @model_validator(mode="after")
    def _fields_of_the_kind(self) -> SensorFilter:
        given = {
            k for k in ("cut_on_nm", "cut_off_nm", "table_csv") if getattr(self, k) is not None
        }
        need = {
            "long_pass": {"cut_on_nm"},
            "band_pass": {"cut_on_nm", "cut_off_nm"},
            "table": {"table_csv"},
        }[self.kind]
        for name in sorted(need - given):
            raise ValueError(f"kind = {self.kind!r} needs {name}")
        for name in sorted(given - need):
            raise ValueError(f"{name} is not a field of a kind = {self.kind!r} filter")
        if self.kind == "table" and "transmittance" in self.model_fields_set:
            raise ValueError("transmittance is not a field of a kind = 'table' filter (its T(λ))")
        if self.kind == "band_pass" and not self.cut_on_nm < self.cut_off_nm:  # type: ignore[operator]
            raise ValueError(
                f"cut_on_nm = {self.cut_on_nm:g} must be below cut_off_nm = {self.cut_off_nm:g}"
            )
        if self.table_csv is not None and not self.table_csv.strip():
            raise ValueError("table_csv = '': give the path of a CSV table")
        return self


class Sensor(_Model):
    """The image plane, binned into pixels, and the digital camera that records it.

    Geometry: a chip of ``cols`` × ``rows`` photosites of pitch ``pixel_pitch_um``, centred on
    the lens axis: the picture is pitch × (cols, rows). Or, given ``width_mm`` × ``height_mm``,
    that image field sampled by ``cols`` × ``rows`` pixels: the paper's lens images the 40 × 30
    mm eye area at magnification −1.144 onto a 46 × 34.3 mm field, binned 87 × 65 (below).

    Camera: the paper's optics fix the image field and the working F-number, hence the
    image-plane irradiance E. The digital camera is that optics scaled to a real chip at the same
    working F-number, so each photosite of pitch ``pixel_pitch_um`` receives the same irradiance
    E; the grid ``cols`` × ``rows`` is the sampling of the picture (one photosite per sample, at
    the irradiance averaged over its bin). Mean photo-electrons per pixel

        N̄ = E [W/m²] · p² [m²] · t [s] · QE / (h c / λ),

    then Poisson shot noise, the well clipped at ``full_well_e``, Gaussian read noise
    ``read_noise_e`` (electrons rms), conversion at ``gain_e_per_dn`` electrons per digital
    number plus ``black_level_dn``, rounding, and the ADC range 0 … 2^``adc_bits`` − 1
    (see :mod:`eyelume.detectors.sensor`).

    ``quantum_efficiency`` is either one number in (0, 1], the same at every wavelength (as
    before QE curves existed), or a QE(λ) curve: the name of a built-in curve
    (:data:`QE_CURVES`: ``"nir-global-shutter"``, a typical NIR-enhanced global-shutter CMOS
    pixel, a model from silicon's absorption, see its file) or the path of a CSV table of two
    columns ``wavelength_nm, quantum_efficiency`` (relative to the scene file; wavelengths
    increasing, QE within [0, 1]), linearly interpolated and never extrapolated. Each wavelength
    group's photo-electrons use QE at its wavelength, or over its LEDs' spectrum
    (``leds.spectral_width_nm``; :func:`eyelume.detectors.sensor.electrons_per_w_mm2`; the sum is
    :attr:`eyelume.render.RenderResult.eye_image_at_scene_wavelength`).

    ``filter``: an optional optical filter in front of the sensor (:class:`SensorFilter`), whose
    transmittance multiplies the QE for every light counted; none by default (T = 1).
    """

    width_mm: Positive | None = None
    height_mm: Positive | None = None
    cols: int = Field(87, ge=1, le=4096)
    rows: int = Field(65, ge=1, le=4096)
    pixel_pitch_um: float = Field(3.0, gt=0, le=100)
    exposure_ms: float = Field(20.0, gt=0, le=60_000)
    quantum_efficiency: float | str = 0.30
    full_well_e: float = Field(6000.0, gt=0, le=1e8)
    read_noise_e: NonNegative = 3.0
    gain_e_per_dn: Positive = 6.0
    adc_bits: int = Field(10, ge=1, le=16)
    black_level_dn: NonNegative = 16.0
    filter: SensorFilter | None = None

    @field_validator("quantum_efficiency", mode="before")
    @classmethod
    def _qe_number_or_curve(cls, value):
        """One number in (0, 1], or a non-empty curve name / CSV path (read when used)."""
        if isinstance(value, bool):
            raise ValueError(f"{value!r}: give a number in (0, 1] or a QE curve (name or CSV)")
        if isinstance(value, int | float):
            if not (math.isfinite(value) and 0 < value <= 1):
                raise ValueError(f"{value!r}: a quantum efficiency must lie in (0, 1]")
            return float(value)
        if isinstance(value, str):
            if not value.strip():
                raise ValueError("'': give a number in (0, 1], a built-in curve or a CSV path")
            try:
                float(value)
            except ValueError:
                return value
            raise ValueError(f"{value!r} is text: give a number unquoted, or a curve (name or CSV)")
        raise ValueError(f"{value!r}: give a number in (0, 1], a built-in curve or a CSV path")

    @model_validator(mode="after")
    def _black_level_in_range(self) -> Sensor:
        if (self.width_mm is None) != (self.height_mm is None):
            raise ValueError("give both width_mm and height_mm, or neither (the chip's size)")
        full_scale = 2**self.adc_bits - 1
        if self.black_level_dn >= full_scale:
            raise ValueError(
                f"black_level_dn = {self.black_level_dn} must be below the ADC full scale "
                f"2^adc_bits − 1 = {full_scale}"
            )
        return self

    @property
    def field_mm(self) -> tuple[float, float]:
        """The picture's size on the image plane (width, height) mm: ``width_mm`` ×
        ``height_mm`` when given, else the chip's, pitch × (cols, rows)."""
        if self.width_mm is not None and self.height_mm is not None:
            return self.width_mm, self.height_mm
        pitch = self.pixel_pitch_um * 1e-3
        return pitch * self.cols, pitch * self.rows


class EyePlane(_Model):
    """The eye-plane receiver (paper §4.1.2): the world plane through the eye's nominal
    corneal vertex (its :class:`EyePose`; not moved by gaze or slip) normal to the headset's z
    axis, tangent to the cornea in primary gaze; x, y measured from the vertex.

    It records the flux crossing it toward the eye (−z) and does not disturb rays.
    """

    width_mm: Positive = 40.0
    height_mm: Positive = 30.0
    cols: int = Field(21, ge=1, le=4096)
    rows: int = Field(15, ge=1, le=4096)


class Run(_Model):
    """Defaults of a render.

    ``estimator`` picks the method: ``forward`` (plain forward Monte Carlo, ``rays`` rays) or
    ``fast`` (camera-side paths with next-event estimation, ``samples_per_pixel`` per pixel, plus
    ``light_paths_per_pixel`` × pixels × samples_per_pixel / 16 light paths aimed at the cornea;
    see :mod:`eyelume.estimators.fast`). A fast camera path continues from its first Lambertian
    vertex in ``continuation_grid``² cosine-weighted directions, one per stratum, for the light
    the faces send each other (the noisy part of a skin pixel; at least 3² on the iris unless
    ``iris_continuation_grid`` says otherwise): 1
    where aiming through a real prescription dominates a sample's cost (paper2005), 4–5 (16–25
    rays) for a thin-lens camera, whose samples are cheap (vr-offaxis: per-sample noise in the
    median skin pixel 20.6 % → 3.6 % for about 2 × the cost at 4; 2.71 % → 2.20 % for 9.3 →
    12.6 µs from 4 to 5, which lets a 1 % render stop at 2 samples per pixel instead of 3;
    ``benchmarks/eye_image.py``, ``benchmarks/render_split.py``).
    ``iris_continuation_grid``: the grid on the surfaces lit through the cornea (the iris),
    whose continuation rays cross the cornea twice and cost ~3 × a skin vertex's (vr-offaxis:
    ~1.3 µs against ~0.4 µs; there they carry ~2.5 % of the median iris pixel's camera-path
    light but all of its sample-to-sample noise); None: ``continuation_grid``, but at least 3.

    ``indirect``: how the fast estimator gets the indirect light at a camera path's first
    Lambertian vertex x (normal n, reflectance ρ), the ρ/π E_ind(x) of L(x) = ρ/π (E_dir(x) +
    E_ind(x)), E_ind(x) = ∫ L_i(x, ω) cos θ dω over the hemisphere (the light the faces send
    each other): ``"paths"`` (default) by the continuation rays above, for every camera sample
    (unbiased); ``"cache"`` by an irradiance cache (Ward, Rubinstein & Clear 1988, "A ray
    tracing solution for diffuse interreflection", SIGGRAPH '88; here on a regular grid of the
    picture): once per render, at the first vertex x_ij of the chief ray through picture
    point (i k, j k) (k = ``indirect_cache_spacing`` pixels), Ê_ij/π from
    ``indirect_cache_grid``² stratified continuation rays; a camera sample's vertex x in the
    cell then takes Σ w_ij Ê_ij / π Σ w_ij, w_ij the bilinear weights of its picture point,
    over the cell's four points that lie on x's surface, within their reach of x (1.5 × the
    world distance to the farthest of their row and column neighbours on the same face with a
    normal alike) and whose normal is within ~18° of n — a point across an edge, a fold, a lash
    or a depth step is not read; with none left (and on the iris, lit through the cornea) the
    sample continues by paths. Bias: the interpolation's, ≈ ⅛ h² ∂²E_ind over a cell of world
    size h where E_ind curves (it is smooth over skin and sclera: the faces it comes from are
    centimetres away), and each point's Monte Carlo error, shared by the ~k² pixels that read
    it, so not in the per-pixel variance the estimator reports (a fixed pattern: the cache
    points' own variance is kept, ``CameraTables.indirect``; on a vr-offaxis person at 400 ×
    400, k = 4, 12² rays, a median 0.5 % of a skin pixel, measured by two cache seeds under the
    same camera samples). The camera samples' variance then has no continuation term, so a
    render to a target error stops at fewer samples (``benchmarks/population.py``);
    ``tests/estimators/test_indirect_cache.py`` compares it with ``"paths"``. k = 8 (the
    default; 4 before): a quarter of the points, ~0.12 instead of ~0.46 CPU-s a 400 × 400
    frame, the camera samples' cost unchanged (no more of them continue by paths); the picture
    moves from k = 4's by a median 0.60 % and 0.51 % of a skin pixel on two people where a
    second cache seed at k = 4 moves it by 0.50 % and 0.46 % (the interpolation's share ~0.3 %
    in quadrature, under the ~1.8 % the sensor's noise target allows a pixel), and the
    regions' means agree with ``"paths"`` as k = 4's do.
    """

    estimator: Literal["forward", "fast"] = "fast"
    rays: int = Field(1_500_000, ge=1)
    samples_per_pixel: int = Field(32, ge=1, le=1_000_000)
    light_paths_per_pixel: float = Field(16.0, ge=0.0, le=1e6)
    continuation_grid: int = Field(2, ge=1, le=8)
    iris_continuation_grid: int | None = Field(None, ge=1, le=8)
    indirect: Literal["paths", "cache"] = "paths"
    indirect_cache_spacing: int = Field(8, ge=1, le=64)
    indirect_cache_grid: int = Field(12, ge=1, le=64)
    seed: int = Field(0, ge=0, lt=2**63)
    batch_size: int = Field(1 << 18, ge=1)
    max_events: int = Field(64, ge=2, le=10_000)


#: Element kinds (:class:`Element`).
ELEMENT_KINDS = ("lens", "mirror", "plate")


class Coating(_Model):
    """The reflectance model of one optical surface of an element (:class:`Element`).

    ``model``:

    * ``"fresnel"``: uncoated; R = (R_s + R_p)/2, the unpolarised Fresnel reflectance from the
      indices either side at the ray's angle of incidence (as the cornea's), T = 1 − R, nothing
      absorbed (at normal incidence R = ((n − 1)/(n + 1))²). A mirror (air on both sides) has
      no Fresnel reflection: it takes ``"fixed"`` or ``"table"``.
    * ``"fixed"``: ``reflectance`` R and ``transmittance`` T at every angle (a coating's or a
      hot mirror's value at the scene's infrared wavelength), the rest A = 1 − R − T absorbed
      by the surface (the ledger's entry of its element); R + T ≤ 1. With ``cutoff_nm`` (a
      hot mirror's edge, idealised as a step): R and T hold at wavelengths ≥ the cut-off, and
      ``reflectance_below`` and ``transmittance_below`` below it (each LED's wavelength group
      is traced with its own).
    * ``"table"``: a CSV file ``table_csv`` of two columns, angle of incidence in degrees
      (increasing from 0 to 90, at most 128 rows) and R (0 … 1) at the scene's wavelength,
      T = 1 − R, R linear in the angle between rows; or of three, angle, wavelength (nm) and
      R, each wavelength's rows a curve of their own, R linear in the wavelength between the
      two curves about each wavelength group's (never extrapolated:
      :func:`eyelume.scene.elements.read_reflectance_table`); ``source`` names where the
      numbers come from (a datasheet, a measurement). Read when the scene is compiled.
    """

    model: Literal["fresnel", "fixed", "table"] = "fresnel"
    reflectance: Fraction | None = None
    transmittance: Fraction | None = None
    table_csv: str | None = None
    source: str = ""
    cutoff_nm: float | None = Field(None, ge=WAVELENGTH_RANGE_NM[0], le=WAVELENGTH_RANGE_NM[1])
    reflectance_below: Fraction | None = None
    transmittance_below: Fraction | None = None

    @model_validator(mode="after")
    def _fields_of_the_model(self) -> Coating:
        fixed = (self.reflectance, self.transmittance)
        below = (self.reflectance_below, self.transmittance_below)
        if self.model == "fixed":
            self._check_fixed()
        elif any(v is not None for v in (*fixed, *below, self.cutoff_nm)):
            raise ValueError(
                "reflectance, transmittance and the cut-off fields belong to model 'fixed', "
                f"not {self.model!r}"
            )
        if self.model == "table":
            if not self.table_csv:
                raise ValueError("model 'table' needs table_csv, the path of the R(angle) CSV")
            if not self.source.strip():
                raise ValueError("model 'table' needs source: where its numbers come from")
        elif self.table_csv is not None:
            raise ValueError(f"table_csv belongs to model 'table', not {self.model!r}")
        return self

    def _check_fixed(self) -> None:
        pairs = [("", self.reflectance, self.transmittance)]
        below = (self.reflectance_below, self.transmittance_below)
        if self.cutoff_nm is not None:
            pairs.append(("_below", *below))
        elif any(v is not None for v in below):
            raise ValueError("reflectance_below and transmittance_below need cutoff_nm")
        for tag, r, t in pairs:
            if r is None or t is None:
                raise ValueError(
                    f"model 'fixed' needs reflectance{tag} and transmittance{tag} (0 … 1)"
                )
            if r + t > 1.0:
                raise ValueError(f"reflectance{tag} + transmittance{tag} = {r + t:g} exceeds 1")

    def fixed_at(self, wavelength_nm: float) -> tuple[float, float]:
        """(R, T) of a ``fixed`` coating at ``wavelength_nm``: the values at and above
        ``cutoff_nm`` (or everywhere without one), the ``_below`` ones under it."""
        if self.cutoff_nm is not None and wavelength_nm < self.cutoff_nm:
            return float(self.reflectance_below), float(self.transmittance_below)  # type: ignore[arg-type]
        return float(self.reflectance), float(self.transmittance)  # type: ignore[arg-type]


#: A perfect mirror's coating, the default of a mirror's surface: R = 1, T = 0.
MIRROR_COATING = Coating(model="fixed", reflectance=1.0, transmittance=0.0)


class ElementSurface(_Model):
    """One surface of an element, in the element's own frame (lens-design convention: the
    element's axis is its local +z, radii positive when the centre of curvature lies farther
    along it): ``radius_mm`` (±inf for a plane), conic constant ``conic`` (0 sphere, −1
    paraboloid) and its ``coating`` (:class:`Coating`; unset: Fresnel on a lens or a plate,
    a perfect mirror, R = 1, on a mirror)."""

    radius_mm: Radius = math.inf
    conic: float = Field(0.0, ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)
    coating: Coating | None = None

    @field_validator("radius_mm")
    @classmethod
    def _radius_not_zero(cls, v: float) -> float:
        if v == 0.0:
            raise ValueError("0 is no radius of curvature: a plane is inf (or leave it unset)")
        return v

    def sag_mm(self, r: float) -> float:
        """Sag z(r) (mm) of the surface at radial distance r (NaN beyond the conicoid)."""
        if math.isinf(self.radius_mm) or self.radius_mm == 0.0:
            return 0.0
        c = 1.0 / self.radius_mm
        arg = 1.0 - (1.0 + self.conic) * c * c * r * r
        return math.nan if arg < 0.0 else c * r * r / (1.0 + math.sqrt(arg))


class Element(_Model):
    """An optical element between the eye, the LEDs and the camera, placed in the world frame
    like the camera (:class:`Camera`): ``position_mm`` is its first surface's vertex, and its
    axis (its local +z, from the first surface to the second) is ``direction`` or points at
    ``look_at_mm`` (unset: world +z, from the eye toward the headset). Every element is
    rotationally symmetric about its axis with a circular clear aperture of
    ``semi_diameter_mm``.

    ``kind``:

    * ``"lens"``: two conic surfaces ``front`` and ``back`` (:class:`ElementSurface`),
      ``thickness_mm`` apart on the axis, of ``glass`` (a name in the glass catalogs the lens
      prescription uses: ``lens.glass_catalogs`` or the shipped ``eyelume.agf``), closed by an
      absorbing cylindrical edge at the clear aperture;
    * ``"plate"``: a window, a lens whose two surfaces are planes;
    * ``"mirror"``: one surface ``front`` (plane, or curved by its radius and conic) of no
      thickness, its coating acting the same from both sides (default R = 1); a hot mirror is a
      mirror with a ``fixed`` coating of its reflectance R and transmittance T at the infrared
      wavelength of the scene.

    What a coating or an edge absorbs is the ledger entry ``element k (name)``. The glass
    itself is taken as clear (no bulk absorption).
    """

    kind: Literal["lens", "mirror", "plate"]
    name: str = ""
    position_mm: Vector3
    direction: Vector3 | None = None
    look_at_mm: Vector3 | None = None
    semi_diameter_mm: Positive
    thickness_mm: Positive | None = None
    glass: str = ""
    front: ElementSurface = ElementSurface()
    back: ElementSurface | None = None

    @model_validator(mode="after")
    def _fields_of_the_kind(self) -> Element:
        if self.look_at_mm is not None and self.direction is not None:
            raise ValueError("give look_at_mm or direction, not both")
        if self.direction is not None and not any(self.direction):
            raise ValueError("direction = (0, 0, 0) has no direction")
        if self.look_at_mm is not None and tuple(self.look_at_mm) == tuple(self.position_mm):
            raise ValueError(f"look_at_mm = {list(self.look_at_mm)} equals position_mm")
        if self.kind == "mirror":
            self._check_mirror()
        else:
            self._check_solid()
        self._check_surfaces()
        return self

    def _check_mirror(self) -> None:
        for name in ("thickness_mm", "back"):
            if getattr(self, name) is not None:
                raise ValueError(f"a mirror has no {name} (one surface, no thickness)")
        if self.glass:
            raise ValueError(f"a mirror has no glass (got {self.glass!r})")
        if self.front.coating is not None and self.front.coating.model == "fresnel":
            raise ValueError(
                "front.coating.model = 'fresnel': a mirror has air on both sides and no "
                "Fresnel reflection; give model 'fixed' (reflectance, transmittance)"
            )

    def _check_solid(self) -> None:
        if self.thickness_mm is None:
            raise ValueError(f"a {self.kind} needs thickness_mm (its centre thickness)")
        if not self.glass.strip():
            raise ValueError(f"a {self.kind} needs glass (a name in the glass catalogs)")
        if self.kind == "plate":
            for side, s in (("front", self.front), ("back", self.back)):
                if s is not None and not math.isinf(s.radius_mm):
                    raise ValueError(
                        f"{side}.radius_mm = {s.radius_mm}: a plate's surfaces are planes "
                        "(use kind = 'lens' for curved ones)"
                    )

    def _check_surfaces(self) -> None:
        """Each surface exists out to the clear aperture; a lens's edge is not negative."""
        sd = self.semi_diameter_mm
        for side, s in (("front", self.front), ("back", self.back)):
            if s is not None and math.isnan(s.sag_mm(sd)):
                raise ValueError(
                    f"semi_diameter_mm = {sd}: beyond the {side} surface's conicoid "
                    f"(radius_mm {s.radius_mm}, conic {s.conic})"
                )
        if self.kind != "mirror":
            edge = self.edge_thickness_mm
            if edge < 0.0:
                raise ValueError(
                    f"thickness_mm = {self.thickness_mm}: the surfaces cross before the clear "
                    f"aperture (edge thickness {edge:.3f} mm at semi_diameter_mm {sd})"
                )

    @property
    def surfaces(self) -> list[ElementSurface]:
        """Its optical surfaces in order along its axis, coatings filled in (lens, plate:
        Fresnel; mirror: R = 1)."""
        default = MIRROR_COATING if self.kind == "mirror" else Coating()
        out = [self.front] if self.kind == "mirror" else [self.front, self.back or ElementSurface()]
        return [
            s if s.coating is not None else s.model_copy(update={"coating": default}) for s in out
        ]

    @property
    def edge_thickness_mm(self) -> float:
        """Axial length of the edge at the clear aperture: t + sag_back(sd) − sag_front(sd)
        (mm; 0 for a mirror)."""
        if self.kind == "mirror":
            return 0.0
        sd = self.semi_diameter_mm
        front, back = self.surfaces
        return float(self.thickness_mm) + back.sag_mm(sd) - front.sag_mm(sd)  # type: ignore[arg-type]

    def axis(self) -> tuple[float, float, float]:
        """Its axis in the world frame as the file writes it (not normalised): ``direction``,
        the way to ``look_at_mm``, or world +z."""
        if self.direction is not None:
            return self.direction
        if self.look_at_mm is not None:
            return tuple(t - p for t, p in zip(self.look_at_mm, self.position_mm, strict=True))  # type: ignore[return-value]
        return (0.0, 0.0, 1.0)


class Sun(_Model):
    """Direct sunlight on the face and eye: a distant source of the reference AM1.5 spectrum.

    Direction (toward the sun, in the world (headset) frame as the file writes it for a right
    eye, mirrored with it for a left eye): ŝ = (cos e sin a, sin e, cos e cos a) with elevation
    e = ``elevation_deg`` above the headset's x–z plane (+90°: straight above the head, world
    +y) and azimuth a = ``azimuth_deg`` from world +z (straight ahead of the face, toward the
    headset) toward +x (toward the right eye's nose).

    ``spectrum``: ``"am1.5-direct"`` (ASTM G173-03 direct normal + circumsolar, 900 W/m² over
    280–4000 nm) or ``"am1.5-global"`` (global on a 37° tilt, 1000 W/m²: direct and sky
    together, taken here as all coming from the sun's direction — an upper bound on the
    direct beam). ``scale`` multiplies it (haze, a visor's transmittance, …). The irradiance
    is normal to the sun's direction at the eye; how it is counted by the sensor and traced:
    :func:`eyelume.detectors.sensor.sunlight_band`, :func:`eyelume.compile.compile_scene`.
    """

    elevation_deg: float = Field(45.0, ge=-90.0, le=90.0)
    azimuth_deg: float = Field(0.0, ge=-360.0, le=360.0)
    spectrum: Literal["am1.5-direct", "am1.5-global"] = "am1.5-direct"
    scale: float = Field(1.0, gt=0.0, le=10.0)

    def direction(self) -> tuple[float, float, float]:
        """Unit vector toward the sun, world frame as written (right eye)."""
        e, a = math.radians(self.elevation_deg), math.radians(self.azimuth_deg)
        return (math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a))


class Ambient(_Model):
    """Light that is not the LEDs': ``sun`` (:class:`Sun`), none by default (a closed VR
    headset). Rendered apart from the LEDs so that the signal-to-ambient ratio of the glints
    and the pupil is reported (:mod:`eyelume.analysis.ambient`)."""

    sun: Sun | None = None


class Scene(_Model):
    """A complete eye illumination and imaging system.

    ``eye_pose`` places the eye (and its face and eye plane) in the headset and says which
    eye it is (:class:`EyePose`). ``head_offset_mm`` moves the eye and the face together
    relative to the headset (LEDs, lens, sensor, eye plane): a headset that slips by −d on the
    head is a head offset of +d. ``elements``: optical elements (lenses, plates, mirrors)
    between the eye, the LEDs and the camera (:class:`Element`; traced by the forward
    estimator only, for now).
    """

    name: str
    description: str = ""
    wavelength_nm: float = Field(850.0, ge=WAVELENGTH_RANGE_NM[0], le=WAVELENGTH_RANGE_NM[1])
    leds: LedArray = LedArray()
    eye: Eye
    face: Face = Face()
    eye_pose: EyePose = EyePose()
    head_offset_mm: Vector3 = (0.0, 0.0, 0.0)
    lens: ImagingLens | None = None
    camera: Camera = Camera()
    sensor: Sensor = Sensor()
    eye_plane: EyePlane = EyePlane()
    run: Run = Run()
    elements: list[Element] = []
    ambient: Ambient = Ambient()

    @model_validator(mode="after")
    def _in_dispersion_range(self) -> Scene:
        """Every wavelength traced (the scene's and each LED's) within the eye's dispersion
        model's range, if it has one (Atchison & Smith's 400–1060 nm, also the tear film's)."""
        eye = self.eye
        if eye.dispersion != "atchison_smith_2005" and eye.cornea_reflection != "tear_film":
            return self
        lo, hi = DISPERSION_RANGE_NM
        named = [("wavelength_nm", self.wavelength_nm)]
        lw = self.leds.wavelength_nm
        if isinstance(lw, list):
            named += [(f"leds.wavelength_nm[{k}]", v) for k, v in enumerate(lw)]
        elif lw is not None:
            named.append(("leds.wavelength_nm", lw))
        why = (
            f"eye.dispersion = {eye.dispersion!r}"
            if eye.dispersion == "atchison_smith_2005"
            else "eye.cornea_reflection = 'tear_film'"
        )
        for field, v in named:
            if not lo <= v <= hi:
                raise ValueError(
                    f"{field} = {v:g} nm lies outside {lo:g}-{hi:g} nm, the range of the ocular "
                    f"dispersion model (Atchison & Smith 2005) that {why} uses"
                )
        return self

    @model_validator(mode="after")
    def _optics_given(self) -> Scene:
        if self.camera.optics == "prescription" and self.lens is None:
            raise ValueError(
                "camera.optics = 'prescription' needs a [lens] prescription "
                "(or set camera.optics = 'ideal' with [camera.ideal])"
            )
        return self

    @property
    def object_distance_mm(self) -> float:
        """The distance (mm) from the camera's lens (first vertex, or the thin lens) to the plane
        it images onto the sensor, along its axis."""
        if self.camera.optics == "ideal":
            return self.camera.ideal.focus_distance_mm  # type: ignore[union-attr]
        return self.lens.object_distance_mm  # type: ignore[union-attr]
