#!/usr/bin/env python3
"""Converts the EMPS benchmark's preprocessed CSV (nonlinearbenchmark.org "EMPS", Janot, Gautier and
Brunot 2019; copy from forgi86/sysid-neural-continuous, Apache-2.0) into a flexfarm measurement
record (docs/formats.md): a prismatic axis mapped onto the hub, m -> rad, N -> N m, kg -> kg m^2.

  position (m) = 0.125 q + 0.125,  velocity (m/s) = 0.125 v_est,  force (N) = 35.15 N/V * u_in

usage: scripts/import_emps.py DATA_EMPS_SC.csv tests/data/emps/emps_estimation.csv
"""
import csv
import sys


def main(src, dst):
    with open(src, newline="") as f, open(dst, "w", newline="") as out:
        rows = csv.DictReader(f)
        out.write("t,ref,hub_angle,hub_rate,hub_torque\n")
        for r in rows:
            t = float(r["time_exp"])
            ref = 0.125 * float(r["q_ref"]) + 0.125
            pos = 0.125 * float(r["q_meas"]) + 0.125
            vel = 0.125 * float(r["v_est"])
            force = 35.15 * float(r["u_in"])
            out.write(f"{t:.6f},{ref:.10g},{pos:.10g},{vel:.10g},{force:.10g}\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
