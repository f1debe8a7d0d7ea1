"""`calibrate undistort`: thermal images rectified to a pinhole view through a calibrated lens, and
the before/after figure."""
from __future__ import annotations

import argparse
import io
import json
from pathlib import Path

import cv2

from platform_tools.rig import atomic
from platform_tools.rig.cameras import camera_model
from platform_tools.rig.conventions import UserError, add_output_options, print_json

from calibration.detect import ImageError, list_images, load_image
from calibration.undistort import ModelError, before_after, pinhole_for, read_lens, rectify, remap_tables

FIGURE = "before_after.png"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "undistort", help="rectify thermal images to a pinhole view through a calibrated lens",
        description="Rectify images through a calibrated lens (an mrcal .cameramodel, or the OpenCV YAML "
                    "`calibrate thermal` writes: distortion_model fisheye, rational_polynomial or plumb_bob) "
                    "to a pinhole view of the same size with the stated horizontal field of view, looking "
                    "along the lens' axis: each pinhole pixel's ray is projected through the lens (mrcal.project "
                    "or cv2.fisheye.projectPoints / cv2.projectPoints) and the image sampled there by cv2.remap "
                    "(bilinear; 0 outside the calibrated image). Writes DIR/<name>.png per image (the input's "
                    "bit depth), DIR/before_after.png (one image before and after, side by side, 8-bit), "
                    "DIR/rectified.cameramodel (the pinhole) and DIR/undistort.json.")
    p.add_argument("--model", required=True, type=Path, metavar="M", help=".cameramodel or OpenCV .yaml")
    p.add_argument("--images", required=True, metavar="DIR|GLOB", help="a folder of images or a quoted glob")
    p.add_argument("--out", required=True, type=Path, metavar="DIR", help="output folder (replaced whole)")
    p.add_argument("--fov", type=float, default=90.0, metavar="DEG",
                   help="horizontal field of view of the pinhole view, edge to edge (default 90)")
    p.add_argument("--figure", default=None, metavar="NAME",
                   help="the image shown in before_after.png (default: the first)")
    add_output_options(p)
    p.set_defaults(handler=cmd_undistort)


def cmd_undistort(args: argparse.Namespace) -> int:
    try:
        lens = read_lens(args.model)
    except ModelError as exc:
        raise UserError(f"{exc}; nothing written") from None
    try:
        pin = pinhole_for(lens.imagersize, args.fov)
    except ValueError as exc:
        raise UserError(f"--fov: {exc}") from None
    try:
        files = list_images(args.images)
        images = [(f, load_image(f)) for f in files]
    except ImageError as exc:
        raise UserError(f"{exc}; nothing written") from None
    W, H = lens.imagersize
    for f, img in images:
        if (img.shape[1], img.shape[0]) != (W, H):
            raise UserError(f"{f}: {img.shape[1]}x{img.shape[0]} image, the model {args.model} is for "
                            f"{W}x{H}; give images of the camera it calibrates; nothing written")
    names = [f.with_suffix(".png").name for f, _ in images]
    if len(set(names)) != len(names):
        raise UserError(f"{args.images}: two images share a file name; give one folder at a time")
    shown = args.figure or files[0].name
    if shown not in {f.name for f in files}:
        raise UserError(f"--figure {shown}: no such image among {args.images}; nothing written")
    maps = remap_tables(lens, pin)
    valid = float((maps[0] >= 0).mean())
    label = f"pinhole {pin.hfov_deg:g} deg"
    model_text = io.StringIO()
    camera_model("LENSMODEL_PINHOLE", pin.intrinsics(), pin.size).write(
        model_text, note=f"pinhole view from {args.model.name}, horizontal field of view {pin.hfov_deg:g} deg")
    report = {"model": str(args.model), "projection": lens.how, "remap": "cv2.remap, bilinear",
              "pinhole": {"f": pin.f, "cx": pin.cx, "cy": pin.cy, "size": list(pin.size), "hfov_deg": pin.hfov_deg},
              "valid_share": valid, "images": len(images), "figure": FIGURE, "figure_image": shown,
              "out": str(args.out)}
    with atomic.OutputDir(args.out) as stage:
        for (f, img), name in zip(images, names):
            rect = rectify(img, maps)
            if not cv2.imwrite(str(stage / name), rect):
                raise UserError(f"{f}: cannot write its rectified image as PNG")
            if f.name == shown:
                cv2.imwrite(str(stage / FIGURE), before_after(img, rect, (f"{f.name} as recorded", label)))
        (stage / "rectified.cameramodel").write_text(model_text.getvalue())
        (stage / "undistort.json").write_text(json.dumps(report, indent=1))
    if args.json:
        print_json(report)
    elif not args.quiet:
        print(f"{args.out}: {len(images)} images rectified to a {pin.size[0]}x{pin.size[1]} pinhole view, "
              f"{pin.hfov_deg:g} deg across (f {pin.f:.1f} px; {lens.how} + cv2.remap), {FIGURE}")
    return 0
