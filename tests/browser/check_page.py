#!/usr/bin/env python3
"""Checks what headless Chromium saw of a `nec view` page (see check_view.sh).

  check_page.py --dom DOM.html --expected EXPECTED.tsv --time SECONDS --screenshot VIEW.png --logs LOG...
                [--caption TEXT]

EXPECTED.tsv: name, joints, end sites, frames, fps, asset (1: shown with its mesh) per clip, as `nec info`
reads them; SECONDS: the time the page was opened at (view.html#t=SECONDS).
Prints one line per clip and per check; exit status 1 when any fails.
"""
import argparse
import html
import json
import re
import struct
import sys
import zlib

REFERENCE_TOLERANCE = 1e-4  # joint positions vs nec's forward kinematics, in body sizes
MESH_TOLERANCE = 1e-3       # an asset's bones (three.js GLTFLoader + AnimationMixer) vs nec's joints, in body sizes


def page_status(dom):
    match = re.search(r'<pre id="nec-status"[^>]*>(.*?)</pre>', dom, re.S)
    if not match:
        raise ValueError("no <pre id=\"nec-status\"> in the DOM")
    return json.loads(html.unescape(match.group(1)))


def png_pixels(path):
    """(width, height, rows of (r, g, b) tuples) of an 8-bit RGB or RGBA PNG."""
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path} is not a PNG")
    at, idat = 8, b""
    while at < len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + length]
        if kind == b"IHDR":
            width, height, depth, color = struct.unpack(">IIBB", body[:10])
            if depth != 8 or color not in (2, 6):
                raise ValueError(f"{path}: unsupported PNG (depth {depth}, color type {color})")
            channels = 3 if color == 2 else 4
        elif kind == b"IDAT":
            idat += body
        at += 12 + length
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = previous[i]
            c = previous[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x * channels:x * channels + 3]) for x in range(width)])
        previous = line
    return width, height, rows


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--dom", required=True)
    parser.add_argument("--expected", required=True)
    parser.add_argument("--time", type=float, required=True)
    parser.add_argument("--screenshot", required=True)
    parser.add_argument("--logs", nargs="*", default=[])
    parser.add_argument("--caption")
    args = parser.parse_args()
    problems = []

    dom = open(args.dom, encoding="utf-8").read()
    try:
        status = page_status(dom)
    except ValueError as error:
        print(f"browser: FAIL {error}")
        return 1
    if status.get("state") != "ready" or not status.get("ok"):
        problems.append(f"page state {status.get('state')!r}, errors: {status.get('errors')}")
    if status.get("errors"):
        problems.append(f"page errors: {status['errors']}")
    if status.get("visible") is not True:
        problems.append("not every joint is in view after framing")

    expected = [line.rstrip("\n").split("\t") for line in open(args.expected) if line.strip()]
    loaded = status.get("clips", [])
    if len(loaded) != len(expected):
        problems.append(f"page loaded {len(loaded)} clips, expected {len(expected)}")
    for (name, joints, end_sites, frames, fps, asset), clip in zip(expected, loaded):
        frames, fps = int(frames), float(fps)
        shown = round(min(args.time, (frames - 1) / fps) * fps)
        want = {"name": name, "joints": int(joints), "end_sites": int(end_sites), "frames": frames, "frame": shown}
        got = {key: clip.get(key) for key in want}
        line = (f"browser: {name}: {got['joints']} joints, {got['end_sites']} end sites, {got['frames']} frames, "
                f"frame {got['frame']} at {args.time} s, joints within {clip.get('reference_error')} body sizes "
                f"of nec's FK, scale {clip.get('scale')}")
        print(line)
        if got != want:
            problems.append(f"{name}: page loaded {got}, nec reads {want}")
        if not (clip.get("reference_error", 1) <= REFERENCE_TOLERANCE):
            problems.append(f"{name}: joints {clip.get('reference_error')} body sizes from nec's FK")
        if asset == "1":
            print(f"browser: {name}: {clip.get('skinned_meshes')} skinned mesh(es), bones within "
                  f"{clip.get('mesh_error')} body sizes of nec's joints")
            if not clip.get("skinned_meshes"):
                problems.append(f"{name}: the asset's skinned mesh did not load")
            if not (clip.get("mesh_error", 1) <= MESH_TOLERANCE):
                problems.append(f"{name}: the asset's bones {clip.get('mesh_error')} body sizes from nec's joints")
    if args.caption and html.escape(args.caption) not in dom:
        problems.append(f"caption {args.caption!r} is not in the page")

    if status.get("warnings"):
        problems.append(f"page warnings: {status['warnings']}")
    # Chromium logs every console message at INFO level; uncaught exceptions are the ones to catch
    # here (the page itself records console.error and console.warn calls in its status).
    for log in args.logs:
        for line in open(log, encoding="utf-8", errors="replace"):
            if "CONSOLE" in line and "Uncaught" in line:
                problems.append(f"console: {line.strip()[:300]}")

    width, height, rows = png_pixels(args.screenshot)
    blue = sum(1 for row in rows for r, g, b in row if b > r + 60 and b > g + 20)
    red = sum(1 for row in rows for r, g, b in row if r > b + 60 and r > g + 40)
    print(f"browser: screenshot {width}x{height}: {blue} blue (left) and {red} red (right) bone pixels")
    if (width, height) != (1280, 720):
        problems.append(f"screenshot is {width}x{height}, expected 1280x720")
    if blue < 50 or red < 50:
        problems.append("the screenshot shows no skeletons (too few blue or red pixels)")

    for problem in problems:
        print(f"browser: FAIL {problem}")
    if not problems:
        print(f"browser: passed ({len(loaded)} clips, three.js r{status.get('three')})")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
