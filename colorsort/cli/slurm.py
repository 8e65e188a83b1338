"""Write a SLURM batch script that runs colorsort-collect or colorsort-eval on a Ray cluster it starts.

Example::

    colorsort-slurm --nodes 4 --cpus-per-node 32 --time 04:00:00 --out collect.sbatch -- \\
        colorsort-collect --episodes 20000 --out /shared/datasets/colorsort --resume
    sbatch collect.sbatch

The script starts Ray on every node of the allocation (the head on the first), then runs the
command there with ``--executor ray --address <head>`` and, unless the command gives its own,
``--workers`` (``--envs`` for colorsort-eval) = nodes x CPUs per node. Every node must see the same
file system: the virtual environment (``--venv``, default this one), the output folder and
``~/.ray``. If the job is cut short, submit it again with ``--resume`` in the command: finished
shards are kept. Exit status 0 when written, 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from colorsort.cli.run import guarded
from colorsort.executors.slurm import SlurmJob, job_script


@guarded("colorsort-slurm")
def main(argv: list[str] | None = None) -> int:
    d = SlurmJob()
    parser = argparse.ArgumentParser(prog="colorsort-slurm", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--nodes", type=int, default=d.nodes, help="nodes of the allocation")
    parser.add_argument("--cpus-per-node", type=int, default=d.cpus_per_node, help="CPUs of each node for Ray")
    parser.add_argument("--time", default=d.time, help="wall-time limit, HH:MM:SS")
    parser.add_argument("--partition", default=None, help="SLURM partition (default: the cluster's)")
    parser.add_argument("--venv", default=d.venv, help="virtual environment every node activates")
    parser.add_argument("--port", type=int, default=d.port, help="the Ray head's port")
    parser.add_argument("--out", default=None, help="write the script here (default: print it)")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="-- colorsort-collect ... or -- colorsort-eval ...")
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    script = job_script(SlurmJob(args.nodes, args.cpus_per_node, args.time, args.partition, args.venv, args.port),
                        command)
    if args.out is None:
        print(script, end="")
        return 0
    Path(args.out).write_text(script)
    Path(args.out).chmod(0o755)
    print(f"wrote {args.out}; submit it with: sbatch {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
