#!/usr/bin/env python3
"""Sequences (and a grid of settings) as Dask tasks, one CSV table: the package's batch command.

    PYTHONPATH=build/python python3 examples/python/batch_dask.py SEQ [SEQ ...] --out table.csv \\
        [--grid odometry.levels=3,4 ...] [--workers 4 | --scheduler tcp://HOST:8786]

is `python3 -m flowfusion.batch` with the same arguments (`--help` lists them): a failed sequence
gets its row with the error, metrics that do not apply are empty, and the exit status is non-zero
when any task failed. Its functions (flowfusion.batch.run_task, one row) serve a script of one's own.
"""
import sys

from flowfusion.batch import main

if __name__ == "__main__":
    sys.exit(main())
