"""The Table 3 imaging lens alone: eyelume's sequential kernel against Optiland 0.6.3 (NumPy).

Run from the repository root (needs the ``bench`` extra: ``pip install "optiland==0.6.3"``)::

    python benchmarks/lens_vs_optiland.py            # 10⁶ rays, a minute or two
    python benchmarks/lens_vs_optiland.py --quick    # smoke run

Both tracers get the SAME rays in the same run: start points uniform over the 40 × 30 mm eye plane
(world z = 0), each aimed at a point uniform over the entrance-pupil disc (paraxial image of the
stop, diameter EFL / 2.51). eyelume traces them with ``eyelume.kernels.sequential.trace_lens`` and
the compiled scene's ``lf`` table, inside a Numba loop written here (``prange`` over rays, and a
serial variant); Optiland traces a prescription built from the same table (radii, conics,
thicknesses, object distance 70 mm, stop at surface 6, clear apertures) with constant-index
``IdealMaterial``s holding eyelume's indices at 850 nm, via ``optic.surfaces.trace(RealRays)``.
Their image-plane points are compared ray by ray before any timing is reported.

Prints the figures and how they were run, and appends a JSON line to
``benchmarks/results/lens_vs_optiland.jsonl``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _common as C  # noqa: E402
import numba  # noqa: E402
import numpy as np  # noqa: E402
from lens_block import trace_lens_block  # noqa: E402
from numba import njit, prange  # noqa: E402

import eyelume  # noqa: E402
from eyelume.compile import compile_scene, lens_paraxial  # noqa: E402
from eyelume.kernels import sequential as Q  # noqa: E402
from eyelume.kernels.sequential import LENS_PASSED, trace_lens  # noqa: E402

# Reference figures for this machine (from the brief, not measured here).
REF_OPTILAND_RAYS_S = 0.34e6
REF_BLOCK_256_INTERACTIONS_S = 400e6  # Numba, 256-ray blocks, 12-surface lens, float64
REF_SCALAR_INTERACTIONS_S = 46e6  # one-ray-at-a-time scalar code
TARGET_RATIO = 30.0


# ------------------------------------------------------------------------------------------------
# eyelume side: Numba loops around the package's per-ray kernel
# ------------------------------------------------------------------------------------------------


@njit(parallel=True)
def trace_parallel(lf, image_z, x0, y0, z0, dx, dy, dz, xo, yo, lo, mo, status, met):
    """Trace every ray through the lens (one ray per iteration, prange over rays)."""
    path = np.zeros((1, 3))  # never written: record=False
    for i in prange(x0.shape[0]):
        s, x, y, z, ux, uy, uz, m, _ = trace_lens(
            lf, x0[i], y0[i], z0[i], dx[i], dy[i], dz[i], path, 0, False
        )
        t = (image_z - z) / uz
        xo[i] = x + t * ux
        yo[i] = y + t * uy
        lo[i] = ux
        mo[i] = uy
        status[i] = s
        met[i] = m


@njit(parallel=True)
def trace_blocks(lf, image_z, x0, y0, z0, dx, dy, dz, xo, yo, lo, mo, status, work, block):
    """The package's SIMD block kernel: prange over blocks of ``block`` rays, surface by surface
    inside each block. ``work`` (6, n) holds the rays being traced (copied in, timed)."""
    n = x0.shape[0]
    for b in prange((n + block - 1) // block):
        i0 = b * block
        i1 = min(i0 + block, n)
        work[0, i0:i1] = x0[i0:i1]
        work[1, i0:i1] = y0[i0:i1]
        work[2, i0:i1] = z0[i0:i1]
        work[3, i0:i1] = dx[i0:i1]
        work[4, i0:i1] = dy[i0:i1]
        work[5, i0:i1] = dz[i0:i1]
        trace_lens_block(
            lf,
            work[0, i0:i1],
            work[1, i0:i1],
            work[2, i0:i1],
            work[3, i0:i1],
            work[4, i0:i1],
            work[5, i0:i1],
            status[i0:i1],
        )
        for i in range(i0, i1):
            t = (image_z - work[2, i]) / work[5, i]
            xo[i] = work[0, i] + t * work[3, i]
            yo[i] = work[1, i] + t * work[4, i]
            lo[i] = work[3, i]
            mo[i] = work[4, i]


#: The same loop on one thread (prange runs as range without parallel=True).
trace_serial = njit(trace_parallel.py_func)


# ------------------------------------------------------------------------------------------------
# the rays
# ------------------------------------------------------------------------------------------------


def make_rays(cs, n: int, seed: int) -> dict:
    """Start points uniform over the eye plane, aimed uniformly over the entrance-pupil disc."""
    sc = cs.scene
    par = lens_paraxial(sc, cs.lens_indices)
    efl = par.efl
    epd = efl / sc.lens.f_number
    z_ep = cs.lf[0, Q.L_Z] + par.entrance_pupil_position(cs.stop_index)
    rng = np.random.default_rng(seed)
    w, h = sc.eye_plane.width_mm, sc.eye_plane.height_mm
    x0 = rng.uniform(-w / 2, w / 2, n)
    y0 = rng.uniform(-h / 2, h / 2, n)
    r = 0.5 * epd * np.sqrt(rng.uniform(0.0, 1.0, n))
    phi = rng.uniform(0.0, 2 * math.pi, n)
    d = np.stack([r * np.cos(phi) - x0, r * np.sin(phi) - y0, np.full(n, z_ep)])
    d /= np.linalg.norm(d, axis=0)
    return {
        "x": x0,
        "y": y0,
        "z": np.zeros(n),
        "L": np.ascontiguousarray(d[0]),
        "M": np.ascontiguousarray(d[1]),
        "N": np.ascontiguousarray(d[2]),
        "efl": efl,
        "epd": epd,
        "z_ep": z_ep,
    }


# ------------------------------------------------------------------------------------------------
# Optiland side
# ------------------------------------------------------------------------------------------------


def build_optiland(cs, epd: float):
    """The lens of ``cs.lf`` as an Optiland Optic; surface 1's vertex at Optiland z = 0."""
    from optiland.materials import IdealMaterial
    from optiland.optic import Optic

    lf, sc = cs.lf, cs.scene
    op = Optic(name=sc.lens.name)
    op.surfaces.add(index=0, thickness=float(lf[0, Q.L_Z]), material=IdealMaterial(1.0))
    for j, s in enumerate(sc.lens.surfaces):
        c = lf[j, Q.L_CURV]
        op.surfaces.add(
            index=j + 1,
            radius=math.inf if c == 0.0 else 1.0 / c,
            conic=float(lf[j, Q.L_CONIC]),
            thickness=float(s.thickness_mm),  # the last one: last vertex → image plane
            material=IdealMaterial(float(lf[j, Q.L_N1])),
            aperture=2.0 * float(lf[j, Q.L_SD]),  # a number is a diameter in Optiland
            is_stop=j == cs.stop_index,
        )
    op.surfaces.add(index=len(sc.lens.surfaces) + 1)
    op.set_aperture("EPD", float(epd))
    op.fields.set_type("object_height")
    op.fields.add(y=0.0)
    op.fields.add(y=math.hypot(sc.eye_plane.width_mm, sc.eye_plane.height_mm) / 2)  # corner
    op.wavelengths.add(cs.scene.wavelength_nm / 1000.0, is_primary=True)
    return op


def optiland_rays(rays: dict, z_shift: float, wavelength_um: float):
    from optiland.rays import RealRays

    n = rays["x"].shape[0]
    return RealRays(
        rays["x"].copy(),
        rays["y"].copy(),
        rays["z"] - z_shift,
        rays["L"].copy(),
        rays["M"].copy(),
        rays["N"].copy(),
        np.ones(n),
        np.full(n, wavelength_um),
    )


# ------------------------------------------------------------------------------------------------


def _parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true", help="smoke run: 10⁵ rays, 2 repeats")
    p.add_argument("--rays", type=int, default=1_000_000)
    p.add_argument("--repeats", type=int, default=5, help="eyelume repeats")
    p.add_argument("--optiland-repeats", type=int, default=3)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--block", type=int, default=256, help="rays per block for the block kernel")
    p.add_argument(
        "--no-optiland-extras",
        action="store_true",
        help="skip the secondary Optiland timings: surfaces.trace(record=True) on the same rays, "
        "and trace_generic (its own ray generation from normalised field/pupil coordinates)",
    )
    a = p.parse_args(argv)
    if a.quick:
        a.rays, a.repeats, a.optiland_repeats = 100_000, 2, 2
    return a


@dataclass
class EyelumeRun:
    """The eyelume side: image-plane points of the per-ray kernel and the timings."""

    out: dict[str, np.ndarray]  # "x", "y" (mm), "L", "M" at the image plane
    status: np.ndarray  # LENS_PASSED, ... per ray
    passed: np.ndarray  # bool, status == LENS_PASSED
    met_total: int  # surfaces met, summed over rays
    threads: int
    t_par: dict
    t_ser: dict
    t_blk: dict
    t_blk1: dict
    jit_s: dict[str, float]  # first call (compile + run): "prange", "serial", "block"
    block_same_status: bool
    block_max_diff: float


def time_eyelume(cs, rays: dict, a: argparse.Namespace) -> EyelumeRun:
    """Trace the rays with the per-ray kernel (prange, serial) and the block kernel, timed; the
    block kernel's fates and image points are compared with the per-ray kernel's."""
    n = a.rays
    out = {k: np.empty(n) for k in ("x", "y", "L", "M")}
    status = np.empty(n, dtype=np.int64)
    met = np.empty(n, dtype=np.int64)
    rays_in = (rays["x"], rays["y"], rays["z"], rays["L"], rays["M"], rays["N"])
    args = (cs.lf, cs.image_z, *rays_in, out["x"], out["y"], out["L"], out["M"], status, met)
    t0 = time.perf_counter()
    trace_parallel(*args)
    t_jit_par = time.perf_counter() - t0
    t0 = time.perf_counter()
    trace_serial(*args)
    t_jit_ser = time.perf_counter() - t0
    threads = numba.get_num_threads()
    t_par = C.timed(lambda: trace_parallel(*args), a.repeats, threads)
    t_ser = C.timed(lambda: trace_serial(*args), a.repeats, 1)
    t_par.pop("last")
    t_ser.pop("last")
    passed = status == LENS_PASSED
    # the block kernel, on copies of the same rays; it must reproduce the per-ray kernel
    out_b = {k: np.empty(n) for k in ("x", "y", "L", "M")}
    status_b = np.empty(n, dtype=np.int64)
    work = np.empty((6, n))
    args_b = (*args[:8], out_b["x"], out_b["y"], out_b["L"], out_b["M"], status_b)
    t0 = time.perf_counter()
    trace_blocks(*args_b, work, a.block)
    t_jit_blk = time.perf_counter() - t0
    t_blk = C.timed(lambda: trace_blocks(*args_b, work, a.block), a.repeats, threads)
    numba.set_num_threads(1)
    t_blk1 = C.timed(lambda: trace_blocks(*args_b, work, a.block), a.repeats, 1)
    numba.set_num_threads(threads)
    t_blk.pop("last")
    t_blk1.pop("last")
    blk_vs_ray = (
        float(max(np.max(np.abs(out_b[k][passed] - out[k][passed])) for k in out))
        if passed.any()
        else math.nan
    )
    return EyelumeRun(
        out=out,
        status=status,
        passed=passed,
        met_total=int(met.sum()),
        threads=threads,
        t_par=t_par,
        t_ser=t_ser,
        t_blk=t_blk,
        t_blk1=t_blk1,
        jit_s={"prange": t_jit_par, "serial": t_jit_ser, "block": t_jit_blk},
        block_same_status=bool(np.array_equal(status_b, status)),
        block_max_diff=blk_vs_ray,
    )


@dataclass
class OptilandRun:
    """The Optiland side: the last traced rays, its EFL and the timings."""

    traced: object  # optiland.rays.RealRays after surfaces.trace
    z_shift: float  # world z of Optiland's z = 0 (the first vertex)
    efl: float
    t_trace: dict
    t_trace_record: dict | None
    t_generic: dict | None


def time_optiland(cs, rays: dict, a: argparse.Namespace) -> OptilandRun:
    """Trace the same rays with Optiland's ``surfaces.trace`` (timed), and, unless
    ``--no-optiland-extras``, time ``record=True`` and ``trace_generic`` too."""
    warnings.simplefilter("ignore", DeprecationWarning)
    op = build_optiland(cs, rays["epd"])
    z_shift = float(cs.lf[0, Q.L_Z])  # Optiland puts the first vertex at z = 0
    wl_um = cs.scene.wavelength_nm / 1000.0
    efl_o = float(op.paraxial.f2())
    op.surfaces.trace(optiland_rays(rays, z_shift, wl_um), record=False)  # warm-up
    batches = [optiland_rays(rays, z_shift, wl_um) for _ in range(a.optiland_repeats)]
    traced = []

    def run_optiland(record: bool):
        r = batches.pop()
        op.surfaces.trace(r, record=record)
        traced.append(r)
        return r

    t_opt = C.timed(lambda: run_optiland(False), a.optiland_repeats, 1)
    t_opt.pop("last")
    t_opt_rec = t_gen = None
    if not a.no_optiland_extras:
        batches = [optiland_rays(rays, z_shift, wl_um) for _ in range(a.optiland_repeats)]
        t_opt_rec = C.timed(lambda: run_optiland(True), a.optiland_repeats, 1)
        t_opt_rec.pop("last")
        t_gen = _time_trace_generic(op, cs, a, wl_um)
    ro = traced[-1]
    batches.clear()
    return OptilandRun(ro, z_shift, efl_o, t_opt, t_opt_rec, t_gen)


def _time_trace_generic(op, cs, a: argparse.Namespace, wl_um: float) -> dict:
    """trace_generic: the same eye-plane field (normalised to the 25 mm corner) and a uniform
    pupil disc, but Optiland generates and aims the rays itself (other rays: timing only)."""
    n = a.rays
    g = np.random.default_rng(a.seed + 1)
    hmax = float(op.fields.max_field)
    hx = g.uniform(-0.5, 0.5, n) * cs.scene.eye_plane.width_mm / hmax
    hy = g.uniform(-0.5, 0.5, n) * cs.scene.eye_plane.height_mm / hmax
    pr, pa = np.sqrt(g.uniform(0, 1, n)) * 0.999, g.uniform(0, 2 * math.pi, n)
    px, py = pr * np.cos(pa), pr * np.sin(pa)
    op.ray_tracer.trace_generic(hx[:1000], hy[:1000], px[:1000], py[:1000], wl_um)
    t_gen = C.timed(
        lambda: op.ray_tracer.trace_generic(hx, hy, px, py, wl_um, record=False),
        a.optiland_repeats,
        1,
    )
    t_gen.pop("last")
    return t_gen


def compare(rays: dict, ey: EyelumeRun, op: OptilandRun) -> tuple[dict, bool]:
    """Image-plane agreement of the rays that pass both tracers, printed; (record, agree)."""
    ro, out, passed_e = op.traced, ey.out, ey.passed
    xo, yo = np.asarray(ro.x), np.asarray(ro.y)
    passed_o = (np.asarray(ro.i) > 0) & np.isfinite(xo) & np.isfinite(yo)
    both = passed_e & passed_o

    def max_diff(theirs: np.ndarray, ours: np.ndarray) -> float:
        return float(np.max(np.abs(theirs[both] - ours[both]))) if both.any() else math.nan

    dx, dy = max_diff(xo, out["x"]), max_diff(yo, out["y"])
    dl, dm = max_diff(np.asarray(ro.L), out["L"]), max_diff(np.asarray(ro.M), out["M"])
    z_img = np.unique(np.asarray(ro.z)[both] + op.z_shift)
    only_e = int((passed_e & ~passed_o).sum())
    only_o = int((~passed_e & passed_o).sum())
    agreement = {
        "passed_eyelume": int(passed_e.sum()),
        "passed_optiland": int(passed_o.sum()),
        "passed_only_eyelume": only_e,
        "passed_only_optiland": only_o,
        "max_abs_dx_mm": dx,
        "max_abs_dy_mm": dy,
        "max_abs_dL": dl,
        "max_abs_dM": dm,
        "optiland_image_z_world_mm": z_img.tolist()[:3],
        "efl_eyelume_mm": rays["efl"],
        "efl_optiland_mm": op.efl,
    }
    print("\n-- agreement (image plane, rays passing both)")
    print(
        f"   passed: eyelume {passed_e.sum():_}, Optiland {passed_o.sum():_} "
        f"({passed_e.mean():.3%}); only eyelume {only_e}, only Optiland {only_o}"
    )
    print(
        f"   max |Δx| = {dx:.3e} mm, max |Δy| = {dy:.3e} mm, max |ΔL| = {dl:.2e}, "
        f"max |ΔM| = {dm:.2e}"
    )
    print(
        f"   EFL eyelume {rays['efl']:.9f} mm, Optiland {op.efl:.9f} mm; Optiland image "
        f"plane at world z = {z_img[:3]}"
    )
    ok = only_e == 0 and only_o == 0 and max(dx, dy) < 1e-9
    print(f"   {'AGREE' if ok else 'DISAGREE'} (criterion: same rays pass, |Δ| < 1e-9 mm)")
    return agreement, ok


def _rate(n: int, t: dict | None) -> float | None:
    return None if t is None else n / t["best_s"]


def print_speed(a: argparse.Namespace, n_surf: int, ey: EyelumeRun, op: OptilandRun) -> None:
    """The timings, their ratios and the brief's reference figures."""
    n, threads = a.rays, ey.threads
    rs_par, rs_ser, rs_opt = _rate(n, ey.t_par), _rate(n, ey.t_ser), _rate(n, op.t_trace)
    rs_blk, rs_blk1 = _rate(n, ey.t_blk), _rate(n, ey.t_blk1)
    print("\n-- speed (best of repeats; spread = (worst − best) / best)")

    def line(name, t, rate, th):
        util = t["cpu_util"]
        warn = C.disturbed(t)
        print(
            f"   {name:<38} {C.fmt_rate(rate)}rays/s  {C.fmt_rate(rate * n_surf)}surf/s "
            f"({th} thr)  best {t['best_s']:.4f} s, spread {t['spread_pct']:.1f} %, "
            f"cpu_util {util}, others {t['others_cpu_s']} CPU-s, steal {t['steal_s']} s{warn}"
        )

    line(f"eyelume block kernel ({threads} threads)", ey.t_blk, rs_blk, threads)
    line("eyelume block kernel (1 thread)", ey.t_blk1, rs_blk1, 1)
    line(f"eyelume prange ({threads} threads)", ey.t_par, rs_par, threads)
    line("eyelume serial", ey.t_ser, rs_ser, 1)
    line("Optiland surfaces.trace(record=False)", op.t_trace, rs_opt, 1)
    if op.t_trace_record:
        line(
            "Optiland surfaces.trace(record=True)",
            op.t_trace_record,
            _rate(n, op.t_trace_record),
            1,
        )
        line("Optiland trace_generic(record=False)", op.t_generic, _rate(n, op.t_generic), 1)
    jit = ey.jit_s
    print(
        f"   first call (JIT compile + run): prange {jit['prange']:.2f} s, serial "
        f"{jit['serial']:.2f} s, block {jit['block']:.2f} s"
    )
    print(
        f"   block kernel ({a.block} rays/block) against the per-ray kernel: same fates "
        f"{ey.block_same_status}, max |Δ| {ey.block_max_diff:.2e} (mm, direction cosines)"
    )
    print(
        f"\n   ratio eyelume block kernel / Optiland = {rs_blk / rs_opt:.1f}×  (target ≥ "
        f"{TARGET_RATIO:.0f}×); one thread each: {rs_blk1 / rs_opt:.1f}×; against the brief's "
        f"{C.fmt_rate(REF_OPTILAND_RAYS_S)}rays/s: {rs_blk / REF_OPTILAND_RAYS_S:.1f}×"
    )
    print(
        f"   block kernel surface interactions/s: {C.fmt_rate(rs_blk * n_surf)} "
        f"({rs_blk * n_surf / REF_BLOCK_256_INTERACTIONS_S:.0%} of the 256-ray-block reference)"
    )
    print(
        f"\n   ratio eyelume prange / Optiland = {rs_par / rs_opt:.1f}×  (target ≥ "
        f"{TARGET_RATIO:.0f}×); eyelume serial / Optiland = {rs_ser / rs_opt:.1f}× "
        f"(core for core)"
    )
    print(
        f"   Optiland measured {C.fmt_rate(rs_opt)}rays/s vs the brief's "
        f"{C.fmt_rate(REF_OPTILAND_RAYS_S)}rays/s; eyelume prange against that reference: "
        f"{rs_par / REF_OPTILAND_RAYS_S:.1f}×"
    )
    ia_par, ia_ser = rs_par * n_surf, rs_ser * n_surf
    print(
        f"   eyelume lens-only surface interactions/s (rays × {n_surf} / s): prange "
        f"{C.fmt_rate(ia_par)}, serial {C.fmt_rate(ia_ser)}; surfaces actually met "
        f"({ey.met_total / n:.3f}/ray): prange {C.fmt_rate(ey.met_total / ey.t_par['best_s'])}, "
        f"serial {C.fmt_rate(ey.met_total / ey.t_ser['best_s'])}"
    )
    print(
        f"   references: 256-ray blocks {C.fmt_rate(REF_BLOCK_256_INTERACTIONS_S)}/s "
        f"(eyelume prange at {ia_par / REF_BLOCK_256_INTERACTIONS_S:.1%} of it), scalar "
        f"one-ray-at-a-time {C.fmt_rate(REF_SCALAR_INTERACTIONS_S)}/s (eyelume serial at "
        f"{ia_ser / REF_SCALAR_INTERACTIONS_S:.0%}, prange at "
        f"{ia_par / REF_SCALAR_INTERACTIONS_S:.0%})"
    )
    print(f"   {1e9 / ia_ser:.1f} ns per surface per ray, one thread")


def result_record(
    a, info: dict, n_surf: int, ey: EyelumeRun, op: OptilandRun, agreement: dict, ok: bool
) -> dict:
    """The JSON line appended to ``benchmarks/results/lens_vs_optiland.jsonl``."""
    n, threads = a.rays, ey.threads
    rs_par, rs_ser, rs_opt = _rate(n, ey.t_par), _rate(n, ey.t_ser), _rate(n, op.t_trace)
    rs_blk = _rate(n, ey.t_blk)
    t_opt_rec, t_gen = op.t_trace_record, op.t_generic
    return {
        "machine": info,
        "command": C.command_line(),
        "quick": a.quick,
        "rays": n,
        "seed": a.seed,
        "lens_surfaces": n_surf,
        "agreement": agreement,
        "agree": ok,
        "eyelume_block": {**ey.t_blk, "threads": threads, "block": a.block, "rays_per_s": rs_blk},
        "eyelume_block_1thread": {**ey.t_blk1, "rays_per_s": _rate(n, ey.t_blk1)},
        "block_same_fates_as_per_ray": ey.block_same_status,
        "block_max_abs_diff_vs_per_ray": ey.block_max_diff,
        "ratio_block_vs_optiland": rs_blk / rs_opt,
        "eyelume_prange": {**ey.t_par, "threads": threads, "rays_per_s": rs_par},
        "eyelume_serial": {**ey.t_ser, "rays_per_s": rs_ser},
        "optiland_record_false": {**op.t_trace, "rays_per_s": rs_opt},
        "optiland_record_true": (
            {**t_opt_rec, "rays_per_s": _rate(n, t_opt_rec)} if t_opt_rec is not None else None
        ),
        "optiland_trace_generic": (
            {**t_gen, "rays_per_s": _rate(n, t_gen), "note": "Optiland's own rays, timing only"}
            if t_gen is not None
            else None
        ),
        "ratio_prange_vs_optiland": rs_par / rs_opt,
        "ratio_serial_vs_optiland": rs_ser / rs_opt,
        "interactions_per_s_nominal": {"prange": rs_par * n_surf, "serial": rs_ser * n_surf},
        "surfaces_met_per_ray": ey.met_total / n,
        "jit_first_call_s": {"prange": ey.jit_s["prange"], "serial": ey.jit_s["serial"]},
    }


def main(argv: list[str] | None = None) -> None:
    """Set up, trace and time both tracers on the same rays, compare, print and record."""
    a = _parse_args(argv)

    import optiland
    import optiland.backend as be

    info = C.machine()
    info["optiland"] = getattr(optiland, "__version__", None) or _dist_version("optiland")
    info["optiland_backend"] = be.get_backend()
    C.print_header("Table 3 lens alone: eyelume trace_lens vs Optiland", info)
    print(f"   Optiland {info['optiland']} ({info['optiland_backend']} backend)")

    cs = compile_scene(eyelume.load_scene("paper2005"))
    n_surf = cs.lf.shape[0]
    rays = make_rays(cs, a.rays, a.seed)
    print(
        f"\n   lens: {n_surf} surfaces, EFL {rays['efl']:.4f} mm, EPD {rays['epd']:.4f} mm, "
        f"entrance pupil at world z = {rays['z_ep']:.4f} mm, image plane z = {cs.image_z} mm"
    )
    print(
        f"   rays: {a.rays:_} from the 40 × 30 mm eye plane to the entrance pupil (seed {a.seed})"
    )

    ey = time_eyelume(cs, rays, a)
    op = time_optiland(cs, rays, a)
    agreement, ok = compare(rays, ey, op)
    print_speed(a, n_surf, ey, op)

    info["loadavg_at_end"] = C.loadavg()
    rec = result_record(a, info, n_surf, ey, op, agreement, ok)
    path = C.append_result("lens_vs_optiland", rec)
    print(f"\nloadavg at end {info['loadavg_at_end']}; appended to {path.relative_to(C.REPO)}")


def _dist_version(name: str) -> str | None:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(name)
    except PackageNotFoundError:
        return None


if __name__ == "__main__":
    main()
