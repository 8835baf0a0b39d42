#!/usr/bin/env python3
"""Audit the pattern exports with an independent reader (ezdxf) and an XML parser.

Usage: python3 tests/ezdxf_check.py [DIR]      (DIR defaults to target/pattern-exports)

For every ``*.dxf`` in DIR (not recursive):
  * read it with ezdxf and run ``doc.audit()``: any audit error or fix fails;
  * every block with a boundary (a POLYLINE or LWPOLYLINE on layer ``1``) must
    also have a sew line (layer ``14``) and a ``Piece Name:`` TEXT on layer 1;
  * a ``*.accumark.dxf`` (the Gerber AccuMark profile) must be 7-bit ASCII with
    an empty HEADER section and no TABLES section;
  * if ``X.outlines.json`` sits beside ``X.dxf`` (``{"<piece name>": [[x, y],
    ...]}``, the cut lines in mm), each listed piece's boundary must match it
    point by point within 0.01 mm (the piece name must name exactly one block).
For every ``*.svg`` in DIR: it must parse with ``xml.etree``.

Prints one line per file and a total. Exit status: 0 all passed, 1 a check
failed (or DIR holds no .dxf/.svg file), 2 DIR does not exist, 3 ezdxf is not
installed (``pip install ezdxf``).
"""

import json
import math
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

TOLERANCE_MM = 0.01
BOUNDARY, SEW = "1", "14"
PIECE_NAME = "piece name:"


def decode(text):
    """A DXF string value as text: caret notation (``^J``, ``^ `` for ``^``) and ``\\U+XXXX`` decoded."""

    def caret(m):
        c = m.group(1)
        if c == " ":
            return "^"
        return chr(ord(c) - 64) if "@" <= c <= "_" else m.group(0)

    text = re.sub(r"\^(.)", caret, text)
    return re.sub(r"\\U\+([0-9A-Fa-f]{4})", lambda m: chr(int(m.group(1), 16)), text)


def boundary_blocks(doc):
    """(block name, piece name or None, boundary points, has sew line) for every block with a boundary."""
    out = []
    for block in doc.blocks:
        boundary, sew, name = None, False, None
        for e in block:
            kind, layer = e.dxftype(), e.dxf.layer
            if kind in ("POLYLINE", "LWPOLYLINE"):
                if layer == BOUNDARY and boundary is None:
                    if kind == "POLYLINE":
                        boundary = [(v.dxf.location.x, v.dxf.location.y) for v in e.vertices]
                    else:
                        boundary = [(x, y) for x, y in e.get_points("xy")]
                elif layer == SEW:
                    sew = True
            elif kind == "TEXT" and layer == BOUNDARY and name is None:
                text = decode(e.dxf.text)
                if text.lower().startswith(PIECE_NAME):
                    name = text[len(PIECE_NAME):].strip()
        if boundary is not None:
            if len(boundary) > 1 and boundary[0] == boundary[-1]:
                boundary.pop()
            out.append((block.name, name, boundary, sew))
    return out


def check_dxf(path, ezdxf):
    """Problems found in one DXF (empty: passed) and a short summary."""
    problems = []
    try:
        doc = ezdxf.readfile(path)
    except Exception as e:  # any read failure is a failed check
        return [f"ezdxf cannot read it: {e}"], "unreadable"
    auditor = doc.audit()
    for err in auditor.errors:
        problems.append(f"audit error: {err.message}")
    for fix in auditor.fixes:
        problems.append(f"audit fix: {fix.message}")
    blocks = boundary_blocks(doc)
    for block, name, _, sew in blocks:
        if not sew:
            problems.append(f"block {block}: boundary without sew line (layer {SEW})")
        if name is None:
            problems.append(f"block {block}: no 'Piece Name:' text on layer {BOUNDARY}")
    compared = 0
    sidecar = path.with_name(path.stem + ".outlines.json")
    if sidecar.exists():
        try:
            expected = json.loads(sidecar.read_text(encoding="utf-8"))
        except (OSError, ValueError) as e:
            expected = {}
            problems.append(f"{sidecar.name} unreadable: {e}")
        for piece, outline in expected.items():
            matches = [b for b in blocks if b[1] == piece]
            if len(matches) != 1:
                problems.append(f"piece {piece!r}: {len(matches)} blocks carry that name, expected 1")
                continue
            got = matches[0][2]
            if len(got) != len(outline):
                problems.append(f"piece {piece!r}: {len(got)} boundary points, expected {len(outline)}")
                continue
            err = max((math.hypot(gx - ex, gy - ey) for (gx, gy), (ex, ey) in zip(got, outline)), default=0.0)
            if err > TOLERANCE_MM:
                problems.append(f"piece {piece!r}: boundary differs by {err:.6f} mm (> {TOLERANCE_MM})")
            compared += 1
    if path.name.endswith(".accumark.dxf"):
        problems.extend(check_gerber_profile(path))
    summary = f"{doc.dxfversion}, {len(blocks)} piece blocks, audit {len(auditor.errors)} errors {len(auditor.fixes)} fixes"
    if sidecar.exists():
        summary += f", {compared} outlines compared"
    return problems, summary


def check_gerber_profile(path):
    """The strict R12 form Gerber AccuMark reads (ezdxf's gerber_D6673 add-on): 7-bit ASCII,
    AC1009 (no $ACADVER either: the HEADER is empty), an empty HEADER section, no TABLES section."""
    raw = path.read_bytes()
    problems = []
    if any(b > 127 for b in raw):
        problems.append("not 7-bit ASCII")
    lines = [line.strip() for line in raw.decode("ascii", "replace").splitlines()]
    pairs = list(zip(lines[0::2], lines[1::2]))
    sections, current, header_vars = [], None, 0
    for i, (code, value) in enumerate(pairs):
        if code == "0" and value == "SECTION" and i + 1 < len(pairs) and pairs[i + 1][0] == "2":
            current = pairs[i + 1][1]
            sections.append(current)
        elif code == "0" and value == "ENDSEC":
            current = None
        elif current == "HEADER" and code == "9":
            header_vars += 1
    if "TABLES" in sections:
        problems.append("has a TABLES section")
    if "HEADER" not in sections or header_vars:
        problems.append(f"HEADER not empty ({header_vars} variables)")
    return problems


def check_svg(path):
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        return [f"XML does not parse: {e}"], "unparsable"
    groups = sum(1 for g in root.iter("{http://www.w3.org/2000/svg}g") if g.get("class") == "piece")
    return [], f"{root.get('width')} x {root.get('height')}, {groups} piece groups"


def main(argv):
    folder = Path(argv[1] if len(argv) > 1 else "target/pattern-exports")
    if not folder.is_dir():
        print(f"ezdxf_check: no directory {folder}", file=sys.stderr)
        return 2
    try:
        import ezdxf
    except ImportError:
        print("ezdxf_check: ezdxf is not installed (pip install ezdxf)", file=sys.stderr)
        return 3
    files = sorted(folder.glob("*.dxf")) + sorted(folder.glob("*.svg"))
    if not files:
        print(f"ezdxf_check: no .dxf or .svg file in {folder}")
        return 1
    failed = 0
    for path in files:
        problems, summary = check_dxf(path, ezdxf) if path.suffix == ".dxf" else check_svg(path)
        status = "FAIL" if problems else "ok"
        print(f"{status:4} {path.name}: {summary}")
        for p in problems:
            print(f"     - {p}")
        failed += bool(problems)
    print(f"ezdxf_check total: {len(files)} files, {failed} failing (ezdxf {ezdxf.__version__})")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
