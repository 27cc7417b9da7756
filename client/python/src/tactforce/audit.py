"""Measured sensor data for Audit.AuditModel, read as `tactforce audit
--csv` reads it: columns t,reference,reading[,shear][,trial] (s; the
reference force, N; the sensor's reading in its own units; the tangential
reference force, N; an integer trial id), or per taxel
t,reference,taxel_0,...,taxel_<N-1>[,reading][,shear][,trial] (one column per
taxel, its reading in its own units, in AuditSample.taxels; `reading`
defaults to the taxels' sum, the fingertip force; taxel columns numbered 0..N-1
without gaps, N = `taxels` when given, else the highest index + 1, as
`--taxels N`). Rows with an empty or NaN field are skipped and counted, as the
CLI does; unknown columns are ignored. Two separate streams (--reference,
--reading, clock-offset estimation) are the CLI's: `tactforce audit
--reference R.csv --reading Q.csv`.

    from tactforce.audit import audit_request
    report = client.AuditModel(audit_request("run.csv", reading_units="counts"))
    report = client.AuditModel(audit_request("taxels.csv", taxels=42, blocks=4))
    print(report.summary)

Errors are tactforce._csv.BadInput naming the file, line and column (and
the missing taxel columns); the server checks the rest (time order, sample
count) and names the sample.
"""

from __future__ import annotations

import math
import os
import re
from typing import Dict, List, Optional, Tuple

from tactforce._csv import BadInput, number, open_table
from tactforce.v1 import audit_pb2

COLUMNS = ["t", "reference", "reading"]
MAX_TAXELS = 4096  # audit::kMaxTaxels
_TAXEL = re.compile(r"taxel_(\d+)")


def taxel_columns(path: str, col: Dict[str, int], taxels: Optional[int] = None) -> List[str]:
    """The per-taxel columns taxel_0 ... taxel_<N-1> of a header (N = `taxels`,
    else the highest index + 1; [] when there are none and `taxels` is not
    given); BadInput naming the missing columns or one beyond N."""
    if taxels is not None and not 1 <= taxels <= MAX_TAXELS:
        raise BadInput(f"taxels: must be in [1, {MAX_TAXELS}], got {taxels}")
    indices = [int(m.group(1)) for m in map(_TAXEL.fullmatch, col) if m and int(m.group(1)) <= MAX_TAXELS]
    highest = max(indices, default=-1)
    n = taxels if taxels is not None else highest + 1
    if n == 0:
        return []
    if highest >= n:
        raise BadInput(f"{path}: column 'taxel_{highest}' beyond the {n} taxels expected "
                       f"(taxel_0 ... taxel_{n - 1})")
    names = [f"taxel_{j}" for j in range(n)]
    missing = [name for name in names if name not in col]
    if missing:
        raise BadInput(f"{path}: missing column(s) {', '.join(missing)} "
                       f"(per-taxel data needs taxel_0 ... taxel_{n - 1})")
    return names


def read_samples(path: str, taxels: Optional[int] = None) -> Tuple[List[audit_pb2.AuditSample], int]:
    """(samples, skipped): one AuditSample per row with every field a
    number, and the number of rows skipped for an empty or NaN field.
    Per-taxel columns go into AuditSample.taxels (see the module doc)."""
    col, rows = open_table(path, ["t", "reference"])
    try:
        taxel_names = taxel_columns(path, col, taxels)
        if "reading" not in col and not taxel_names:
            raise BadInput(f"{path}: missing column(s) reading (or per-taxel columns taxel_0 ... taxel_<N-1>)")
    except BadInput:
        # The rows' generator holds the open file: start and close it.
        next(rows, None)
        rows.close()
        raise
    # Taxels before the reading: a bad taxel value also spoils their sum.
    fields = ["t", "reference"] + taxel_names + [name for name in ("reading", "shear", "trial") if name in col]
    samples, skipped = [], 0
    for line, row in rows:
        values = {name: number(path, line, row, col, name, allow_nan=True) for name in fields}
        if any(math.isnan(v) for v in values.values()):
            skipped += 1
            continue
        sample = audit_pb2.AuditSample(t=values["t"], reference=values["reference"])
        sample.taxels.extend(values[name] for name in taxel_names)
        sample.reading = values["reading"] if "reading" in values else math.fsum(sample.taxels)
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
                  max_causes: Optional[int] = None,
                  taxels: Optional[int] = None,
                  blocks: Optional[int] = None) -> audit_pb2.AuditRequest:
    """An AuditRequest of the CSV's samples, named after the file. `taxels`:
    the per-taxel column count expected (the CLI's --taxels); `blocks`: the
    blocked hold-out's block count (--blocks; 0 = off, default 4)."""
    samples, _ = read_samples(path, taxels)
    if not samples:
        raise BadInput(f"{path}: no rows with t, reference and reading all numbers")
    request = audit_pb2.AuditRequest(source=os.path.basename(path), reading_units=reading_units,
                                     model_json=model_json)
    request.samples.extend(samples)
    if heldout_fraction is not None:
        request.heldout_fraction = heldout_fraction
    if max_causes is not None:
        request.max_causes = max_causes
    if blocks is not None:
        if not 0 <= blocks <= 10:
            raise BadInput(f"blocks: must be in [0, 10], got {blocks}")
        request.blocks = blocks
    return request
