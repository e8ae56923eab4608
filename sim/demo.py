"""``rasterhw demo``: the main job on built-in defaults.

1. renders a scene (default ``c300``) through the golden geometry pipeline and the float
   reference rasteriser;
2. runs ``snu-100px`` through the SNU Gouraud scan converter (golden, bit-accurate) and the
   pixel-bus HDL, compares the two frames bit for bit and counts cycles;
3. runs the same ``scene`` through one ZB/M unit (interleave 8) in HDL, compared line by line
   with the bit-accurate ZB/M model;
4. writes PNGs, a diff image, ``summary.json`` and ``report.md`` (the cycle report) under ``out/``.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from PIL import Image
from tqdm import tqdm


def run_demo(out: Path, *, scene: str = "c300", engine: str = "verilator") -> dict:
    from rasterhw.golden_model.compare import compare_images, write_diff_png
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.reference import rasterise
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.golden_model.snu.gouraud import scan_convert
    from rasterhw.golden_model.snu.pixelbus import pixelbus_frame, rgb_image
    from rasterhw.sim.report import format_table, run_report
    from rasterhw.sim.snu.pixelbus import simulate_pixelbus
    from rasterhw.sim.zbm.driver import simulate_zbm

    out.mkdir(parents=True, exist_ok=True)
    summary: dict = {}
    bar = tqdm(total=5, desc="demo", unit="step")

    bar.set_postfix_str(f"{scene}: reference render")
    sc = build_scene(scene)
    t0 = time.perf_counter()
    tris = run_geometry(sc, 512, 512)
    frame = rasterise(tris)
    wall = time.perf_counter() - t0
    ref_png = out / f"{scene}-reference.png"
    frame.save_png(ref_png)
    summary["reference"] = {"scene": scene, "width": 512, "height": 512, **tris.stats,
                            "fragments": int(frame.fragments), "pixels_written": int(frame.pixels_written),
                            "wall_s": round(wall, 4), "image": str(ref_png)}
    bar.update(1)

    bar.set_postfix_str("snu-100px: golden scan conversion")
    snu = build_scene("snu-100px")
    stris = run_geometry(snu, 1280, 1024, z_bits=24, z_far_is_zero=True)
    stream = scan_convert(stris)
    golden_rgb = rgb_image(pixelbus_frame(stream)[0])
    Image.fromarray(golden_rgb).save(out / "snu-100px-golden.png")
    bar.update(1)

    bar.set_postfix_str(f"snu-100px: pixel-bus HDL on {engine}")
    res = simulate_pixelbus(stream, engine=engine, progress=False)
    hdl_rgb = res.pop("frame_rgb")
    snu_run = (stris, stream, res)
    Image.fromarray(hdl_rgb).save(out / f"snu-100px-pixelbus-{engine}.png")
    cmp = compare_images(golden_rgb, hdl_rgb)
    write_diff_png(golden_rgb, hdl_rgb, out / "snu-100px-diff.png")
    summary["pixelbus"] = {"scene": "snu-100px", **res, "image_compare": cmp}
    bar.update(1)

    bar.set_postfix_str(f"{scene}: ZB/M unit HDL on {engine} (first run builds the model, ~1 min)")
    zres = simulate_zbm(sc, 512, 512, interleave=8, units=1, engine=engine)
    Image.fromarray(zres.pop("frame_rgb")).save(out / f"{scene}-zbm-{engine}.png")
    summary["zbm"] = {"scene": scene, **zres}
    bar.update(1)

    bar.set_postfix_str("report snu")
    rows = run_report("snu", out_dir=out / "reproduction", engine=engine, progress=False, snu_100px=snu_run)
    bar.update(1)
    bar.close()

    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=float) + "\n")
    pb = summary["pixelbus"]
    md = [
        "# rasterhw demo", "",
        f"## Reference render: {scene} at 512x512", "",
        f"![{scene}]({ref_png.name})", "",
        f"{summary['reference'].get('polygons_in')} polygons in, {summary['reference'].get('polygons_drawn')} drawn, "
        f"{summary['reference']['fragments']} fragments, {summary['reference']['pixels_written']} pixel writes, "
        f"{summary['reference']['wall_s'] * 1e3:.1f} ms.", "",
        f"## SNU pixel bus: snu-100px at 1280x1024 on {engine}", "",
        f"- pixel writes: {len(stream)}; pixels compared: {pb['pixels_compared']}; mismatches: {pb['mismatches']}",
        f"- HDL cycles: {pb['cycles']} at {pb['clock_hz'] / 1e6:g} MHz = "
        f"{pb['cycles'] / pb['clock_hz'] * 1e3:.2f} ms of bus time "
        f"({len(stream) / (pb['cycles'] / pb['clock_hz']) / 1e6:.2f} Mpixel/s; paper: 12.5 Mpixel/s peak)",
        f"- simulation: {pb['wall_s']:.1f} s wall, {pb['cycles_per_s']:.3g} cycles/s", "",
        f"## ZB/M: {scene} through one unit (interleave 8) on {engine}", "",
        f"![{scene} ZB/M]({scene}-zbm-{engine}.png)", "",
        f"- edge pairs: {summary['zbm']['edge_pairs']}; pixels compared: {summary['zbm']['pixels_compared']}; "
        f"mismatches: {summary['zbm']['mismatches']}",
        f"- HDL cycles: {summary['zbm']['cycles']} at 25 MHz = {summary['zbm']['cycles'] / 25e6 * 1e3:.2f} ms "
        f"({summary['zbm']['polygons_per_s'] / 1e3:.1f} K triangles/s, no skew allowance)",
        f"- simulation: {summary['zbm']['wall_s']:.1f} s wall, {summary['zbm']['cycles_per_s']:.3g} cycles/s", "",
        "## SNU report", "", format_table(rows, markdown=True), "",
        "ZB/M Table 1 from HDL cycles: `rasterhw report zbm` (pysim, ~2 min) -> docs/reproduction/zbm.md.", "",
    ]
    (out / "report.md").write_text("\n".join(md) + "\n")
    print(format_table(rows))
    print(f"\nwrote {out}/report.md, {out}/summary.json and images in {out}/")
    if pb["mismatches"] or summary["zbm"]["mismatches"]:
        raise SystemExit(f"HDL differs from the golden model: pixel bus {pb['mismatches']}, "
                         f"ZB/M {summary['zbm']['mismatches']} mismatches")
    return summary
