#!/usr/bin/env python3
"""A Python client generated from openapi.yaml runs the three flows (issue #16, item 4).

Generates the client with openapi-python-client (PyPI) into a temporary
folder, imports it, and against a running `grade3d serve`:
  1. grades a size chart (JSON body with a SizeChartDocument) and downloads
     a garment GLB and a pattern DXF as bytes;
  2. grades a scan (multipart: GLB, landmarks, template) and downloads its
     GLB and DXF;
  3. submits a batch job (a size chart), polls it to the end and downloads a
     GLB and a DXF of the job.
Every answer is parsed into the generated models (GradeResult, Job, ...).

Usage: tests/client.py --url http://127.0.0.1:PORT --key KEY --out DIR
Run by tests/service.rs (required in CI). Exits non-zero on any failure.
"""

import argparse
import io
import json
import pathlib
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def generate(out: pathlib.Path) -> None:
    """openapi-python-client, without post hooks (no formatter needed)."""
    config = out / "config.yaml"
    config.write_text("post_hooks: []\nproject_name_override: grade3d-client\npackage_name_override: grade3d_client\n")
    pkg = out / "grade3d_client"
    cmd = [
        sys.executable, "-m", "openapi_python_client", "generate",
        "--path", str(ROOT / "openapi.yaml"),
        "--output-path", str(pkg),
        "--config", str(config),
        "--meta", "none",
        "--overwrite",
    ]
    r = subprocess.run(cmd, capture_output=True, text=True)
    print("\n".join(l for l in (r.stdout + r.stderr).splitlines() if l.startswith(("WARNING", "Error", "Unsupported"))))
    if r.returncode != 0 or not (pkg / "__init__.py").exists():
        sys.exit(f"client generation failed ({r.returncode})")
    # the only part it may leave out: the CSV body of the size-chart flow (the JSON body carries CSV text too)
    skipped = [l for l in (r.stdout + r.stderr).splitlines() if l.startswith("WARNING parsing")]
    if any("/v1/grade/size-chart" not in l for l in skipped):
        sys.exit(f"the generated client left out operations: {skipped}")


def check_glb(data: bytes, what: str) -> None:
    assert isinstance(data, bytes) and data[:4] == b"glTF", f"{what}: not a GLB ({data[:16]!r})"


def check_dxf(data: bytes, what: str) -> None:
    text = data.decode("ascii", errors="replace")
    assert text.lstrip().startswith("0") and "SECTION" in text and text.rstrip().endswith("EOF"), f"{what}: not a DXF"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--url", required=True)
    ap.add_argument("--key", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    generate(out)
    sys.path.insert(0, str(out))

    from grade3d_client import AuthenticatedClient
    from grade3d_client.api.grading import grade_scan, grade_size_chart, get_result, get_result_artefact
    from grade3d_client.api.jobs import get_job, get_job_artefact, submit_job
    from grade3d_client.models import (
        GradeResult, Job, JobSpec, JobState, Problem, ScanUpload, SizeChartDocument,
        SizeChartDocumentRow, SizeChartDocumentRowMeasurements, SizeChartRequest,
    )
    from grade3d_client.types import File

    client = AuthenticatedClient(base_url=args.url, token=args.key, timeout=300.0)

    def row(size: str, bust: float, waist: float, hip: float) -> SizeChartDocumentRow:
        m = SizeChartDocumentRowMeasurements()
        m.additional_properties = {"bust_girth": bust, "waist_girth": waist, "hip_girth": hip}
        return SizeChartDocumentRow(size=size, measurements=m)

    chart = SizeChartDocument(sizes=[row("S", 86, 68, 94), row("M", 92, 74, 100)], unit="cm")

    def download(fetch, what: str, check) -> None:
        resp = fetch()
        assert resp.status_code == 200, f"{what}: {resp.status_code} {resp.content[:300]!r}"
        assert isinstance(resp.parsed, File), f"{what}: parsed as {type(resp.parsed)}"
        check(resp.parsed.payload.read(), what)

    def artefacts_of(result, suffix: str) -> str:
        names = [a.name for a in result.artefacts if a.name.endswith(suffix)]
        assert names, f"no {suffix} among {[a.name for a in result.artefacts]}"
        return names[0]

    # 1. the size-chart flow
    r = grade_size_chart.sync_detailed(
        client=client, body=SizeChartRequest(templates=["straight-skirt"], chart=chart, base_size="M")
    )
    assert r.status_code == 200 and isinstance(r.parsed, GradeResult), f"size chart: {r.status_code} {r.content[:500]!r}"
    result = r.parsed
    assert result.report.flow.value == "size-chart", result.report
    assert [s.size for s in result.report.sizes] == ["S", "M"]
    again = get_result.sync(client=client, id=result.id)
    assert isinstance(again, GradeResult) and again.cached, again
    for suffix, check in ((".garment.glb", check_glb), (".pattern.dxf", check_dxf)):
        name = artefacts_of(result, suffix)
        download(lambda: get_result_artefact.sync_detailed(client=client, id=result.id, artefact=name), name, check)
    print("size-chart flow: ok,", len(result.artefacts), "artefacts")

    # a bad chart: a problem naming the field
    bad = grade_size_chart.sync_detailed(
        client=client, body=SizeChartRequest(templates=["no-such-template"], chart=chart)
    )
    assert bad.status_code in (400, 422) and isinstance(bad.parsed, Problem), bad
    assert bad.parsed.field == "templates", bad.parsed

    # 2. the scan flow
    glb = (ROOT / "fixtures/bodies/male-average-asian.glb").read_bytes()
    landmarks = (ROOT / "fixtures/bodies/male-average-asian.landmarks.json").read_text()
    upload = ScanUpload(
        scan=File(payload=io.BytesIO(glb), file_name="scan.glb", mime_type="model/gltf-binary"),
        landmarks=landmarks,
        template="straight-skirt",
    )
    r = grade_scan.sync_detailed(client=client, body=upload)
    assert r.status_code == 200 and isinstance(r.parsed, GradeResult), f"scan: {r.status_code} {r.content[:500]!r}"
    scan = r.parsed
    assert scan.report.flow.value == "scan" and len(scan.report.bodies) == 1, scan.report
    for suffix, check in ((".garment.glb", check_glb), (".pattern.dxf", check_dxf)):
        name = artefacts_of(scan, suffix)
        download(lambda: get_result_artefact.sync_detailed(client=client, id=scan.id, artefact=name), name, check)
    print("scan flow: ok,", len(scan.artefacts), "artefacts")

    # 3. a batch job
    r = submit_job.sync_detailed(client=client, body=JobSpec(templates=["straight-skirt"], size_chart=chart))
    assert r.status_code == 202 and isinstance(r.parsed, Job), f"job: {r.status_code} {r.content[:500]!r}"
    job = r.parsed
    total = job.progress.total
    deadline = time.time() + 600
    while job.state in (JobState.QUEUED, JobState.RUNNING):
        assert time.time() < deadline, "the job did not end in 600 s"
        time.sleep(0.2)
        job = get_job.sync(client=client, id=job.id)
        assert isinstance(job, Job), job
        assert job.progress.total == total, (job.progress, total)
    assert job.state == JobState.DONE, f"job ended {job.state}: {job.error}"
    assert job.report is not None and job.report.flow.value == "size-chart"
    for suffix, check in ((".garment.glb", check_glb), (".pattern.dxf", check_dxf)):
        name = artefacts_of(job, suffix)
        download(lambda: get_job_artefact.sync_detailed(client=client, id=job.id, artefact=name), name, check)
    print("job flow: ok,", len(job.artefacts), "artefacts")
    print(json.dumps({"client": "ok"}))


if __name__ == "__main__":
    main()
