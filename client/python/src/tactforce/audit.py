"""Measured sensor data for Audit.AuditModel, read as `tactforce audit
--csv` reads it: columns t,reference,reading[,shear][,trial] (s; the
reference force, N; the sensor's reading in its own units; the tangential
reference force, N; an integer trial id); rows with an empty or NaN field
are skipped and counted, as the CLI does; unknown columns are ignored. Two
separate streams (--reference, --reading, clock-offset estimation) are the
CLI's: `tactforce audit --reference R.csv --reading Q.csv`.

    from tactforce.audit import audit_request
    report = client.AuditModel(audit_request("run.csv", reading_units="counts"))
    print(report.summary)

Errors are tactforce._csv.BadInput naming the file, line and column; the
server checks the rest (time order, sample count) and names the sample.
"""

from __future__ import annotations

import math
import os
from typing import List, Optional, Tuple

from tactforce._csv import BadInput, number, open_table
from tactforce.v1 import audit_pb2

COLUMNS = ["t", "reference", "reading"]


def read_samples(path: str) -> Tuple[List[audit_pb2.AuditSample], int]:
    """(samples, skipped): one AuditSample per row with every field a
    number, and the number of rows skipped for an empty or NaN field."""
    col, rows = open_table(path, COLUMNS)
    optional = [name for name in ("shear", "trial") if name in col]
    samples, skipped = [], 0
    for line, row in rows:
        values = {name: number(path, line, row, col, name, allow_nan=True) for name in COLUMNS + optional}
        if any(math.isnan(v) for v in values.values()):
            skipped += 1
            continue
        sample = audit_pb2.AuditSample(t=values["t"], reference=values["reference"], reading=values["reading"])
        if "shear" in values:
            sample.shear = values["shear"]
        if "trial" in values:
            trial = values["trial"]
            if trial != int(trial) or abs(trial) > 2**31 - 1:
                raise BadInput(f"{path}:{line}: column 'trial': not an integer in int's range ({trial:g})")
            sample.trial = int(trial)
        samples.append(sample)
    return samples, skipped


def audit_request(path: str, reading_units: str = "", model_json: str = "",
                  heldout_fraction: Optional[float] = None,
                  max_causes: Optional[int] = None) -> audit_pb2.AuditRequest:
    """An AuditRequest of the CSV's samples, named after the file."""
    samples, _ = read_samples(path)
    if not samples:
        raise BadInput(f"{path}: no rows with t, reference and reading all numbers")
    request = audit_pb2.AuditRequest(source=os.path.basename(path), reading_units=reading_units,
                                     model_json=model_json)
    request.samples.extend(samples)
    if heldout_fraction is not None:
        request.heldout_fraction = heldout_fraction
    if max_causes is not None:
        request.max_causes = max_causes
    return request
