"""Slip-trial CSVs for Estimator.EstimateFriction, read as `tactforce
friction` reads them: one file per trial, columns t,fx,fy,fz,px,py,pz[,slip]
(s; the force the probe applies to the object, N; the contact point, m;
slip 0 or 1), times increasing; unknown columns are ignored.

    from tactforce.friction import read_trial, friction_request
    request = friction_request(["trial0.csv", "trial1.csv"], normal=(0, 0, -1))
    print(client.EstimateFriction(request).median)

Errors are tactforce._csv.BadInput naming the file, line and column
("trial0.csv:7: column 'fz': not a number ('x')").
"""

from __future__ import annotations

import os
from typing import Iterable, Optional, Sequence

from tactforce._csv import BadInput, number, open_table
from tactforce.v1 import estimator_pb2

COLUMNS = ["t", "fx", "fy", "fz", "px", "py", "pz"]


def read_trial(path: str, normal: Optional[Sequence[float]] = None,
               name: Optional[str] = None) -> estimator_pb2.FrictionTrial:
    """One trial from `path`; `normal` (into the object) when given, else
    the server takes it from the request's mesh. The name defaults to the
    file name."""
    col, rows = open_table(path, COLUMNS)
    trial = estimator_pb2.FrictionTrial(name=name if name is not None else os.path.basename(path))
    if normal is not None:
        trial.normal.x, trial.normal.y, trial.normal.z = (float(v) for v in normal)
    previous = None
    for line, row in rows:
        values = [number(path, line, row, col, c) for c in COLUMNS]
        if previous is not None and not values[0] > previous:
            raise BadInput(f"{path}:{line}: column 't': not increasing")
        previous = values[0]
        sample = trial.samples.add(t=values[0])
        sample.force.x, sample.force.y, sample.force.z = values[1:4]
        sample.contact_point.x, sample.contact_point.y, sample.contact_point.z = values[4:7]
        if "slip" in col:
            slip = number(path, line, row, col, "slip")
            if slip not in (0.0, 1.0):
                raise BadInput(f"{path}:{line}: column 'slip': must be 0 or 1")
            sample.slip = slip == 1.0
    if not trial.samples:
        raise BadInput(f"{path}: no samples")
    return trial


def friction_request(paths: Iterable[str], normal: Optional[Sequence[float]] = None) -> estimator_pb2.FrictionRequest:
    """A FrictionRequest with one trial per CSV file."""
    request = estimator_pb2.FrictionRequest()
    request.trials.extend(read_trial(path, normal) for path in paths)
    if not request.trials:
        raise BadInput("no trial CSV given")
    return request
