"""A SLURM batch script that starts a Ray cluster on its nodes and runs one colorsort command on it.

It follows Ray's own SLURM recipe: ``ray start --head`` on the first node of the allocation,
``ray start --address`` on the others (each through ``srun``, with all the node's CPUs), then the
command on the first node with ``--executor ray --address <head>``. Every node must see the
same file system (the virtual environment, the output folder, ``~/.ray`` and its auth token).
"""

from __future__ import annotations

import shlex
import sys
from dataclasses import dataclass
from pathlib import Path

from colorsort.config import check_range
from colorsort.errors import ConfigError

COMMANDS = {"colorsort-collect": "--workers", "colorsort-eval": "--envs"}  # the command -> its worker flag


@dataclass(frozen=True)
class SlurmJob:
    """The allocation the script asks for."""

    nodes: int = 2
    cpus_per_node: int = 32  # CPUs of each node given to Ray: one shard (or eval job) each
    time: str = "04:00:00"  # wall-time limit, SLURM's HH:MM:SS
    partition: str | None = None
    venv: str = sys.prefix  # the virtual environment every node activates
    port: int = 6379  # the Ray head's port
    job_name: str = "colorsort"

    def __post_init__(self) -> None:
        check_range("nodes", self.nodes, 1, 10_000)
        check_range("cpus_per_node", self.cpus_per_node, 1, 1024)
        check_range("port", self.port, 1024, 65535)
        if len(self.time.split(":")) != 3 or not all(p.isdigit() for p in self.time.split(":")):
            raise ConfigError(f"time={self.time!r}: give HH:MM:SS, e.g. 04:00:00")


def job_script(job: SlurmJob, command: list[str]) -> str:
    """The sbatch script that runs ``command`` (``colorsort-collect ...`` or ``colorsort-eval ...``) on Ray.

    Raises:
        ValueError: another command, or one that names an executor other than ray.
    """
    if not command or command[0] not in COMMANDS:
        raise ConfigError(f"command {command[:1]}: give one of {list(COMMANDS)}, with its arguments")
    args = list(command)
    if "--executor" in args and args[args.index("--executor") + 1:][:1] != ["ray"]:
        raise ConfigError("the SLURM script runs the command on Ray: leave out --executor, or give --executor ray")
    if "--address" in args:
        raise ConfigError("the SLURM script sets --address to the Ray head it starts: leave it out of the command")
    extra = []
    if "--executor" not in args:
        extra += ["--executor", "ray"]
    if COMMANDS[args[0]] not in args:
        extra += [COMMANDS[args[0]], str(job.nodes * job.cpus_per_node)]
    partition = f"#SBATCH --partition={job.partition}\n" if job.partition else ""
    return f"""#!/bin/bash
#SBATCH --job-name={job.job_name}
#SBATCH --nodes={job.nodes}
#SBATCH --ntasks-per-node=1
#SBATCH --cpus-per-task={job.cpus_per_node}
#SBATCH --time={job.time}
#SBATCH --output={job.job_name}-%j.log
{partition}# Written by colorsort-slurm: a Ray cluster on the allocation, then one colorsort command on it.
set -euo pipefail
source {shlex.quote(str(Path(job.venv) / "bin" / "activate"))}
export MUJOCO_GL="${{MUJOCO_GL:-egl}}" HF_HUB_OFFLINE=1
export RAY_AUTH_MODE=token  # every Ray process of the job uses the token in ~/.ray/auth_token (a shared home)
ray get-auth-token --generate >/dev/null  # `ray start` never makes one: it stops if none is there

nodes=($(scontrol show hostnames "$SLURM_JOB_NODELIST"))
head_ip=$(srun --nodes=1 --ntasks=1 -w "${{nodes[0]}}" hostname --ip-address | awk '{{print $1}}')
address="$head_ip:{job.port}"
srun --nodes=1 --ntasks=1 -w "${{nodes[0]}}" ray start --head --node-ip-address="$head_ip" --port={job.port} \\
    --num-cpus={job.cpus_per_node} --include-dashboard=false --block &
for _ in $(seq 120); do (: > "/dev/tcp/$head_ip/{job.port}") 2>/dev/null && break; sleep 1; done  # the head's GCS
sleep 5  # and its raylet
for node in "${{nodes[@]:1}}"; do
    srun --nodes=1 --ntasks=1 -w "$node" ray start --address="$address" --num-cpus={job.cpus_per_node} --block &
done

status=0
{shlex.join(args + extra)} --address "$address" || status=$?
# Stop this job's Ray nodes only (not `ray stop`, which ends every Ray process on a shared node):
kill $(jobs -p) 2>/dev/null || true
wait || true
exit $status
"""
