"""Ray backend: each job (one run, or seeds trained together) is one Ray task (one CPU),
retried when its worker dies.

``address=None`` starts a Ray instance on this machine (bound to 127.0.0.1, no dashboard);
an address joins a running cluster (``ray start --head`` on one node, ``ray start --address``
on the others). Results come back through a shared filesystem: a task runs ``lili train
--out <DIR>/...`` on its node, so ``--out`` must be the same path on every node (NFS or the
like) and the nodes must have lili installed in the same Python environment. The backend
checks at start that a task can write into ``--out`` and that the driver sees what it wrote.
A retried task looks at the run folder again and resumes from the last checkpoint.
"""

from __future__ import annotations

import secrets
import socket
from pathlib import Path

from lili.errors import shown
from lili.experiments.runner import Job, run_blocking

__all__ = ["RayBackend", "RAY_MISSING", "check_address"]

RAY_MISSING = ("--ray needs Ray, which is not installed; install the extra: "
               "pip install -e '.[ray]' (or pip install 'lili[ray]')")
MAX_RETRIES = 3


def _import_ray():
    try:
        import ray
    except ImportError:
        raise ValueError(RAY_MISSING) from None
    return ray


ADDRESS_TIMEOUT_S = 3.0
"""How long :func:`check_address` waits for the cluster's port to answer."""


def check_address(address: str, timeout: float = ADDRESS_TIMEOUT_S) -> None:
    """ValueError unless ``address`` is ``HOST:PORT`` (or ``ray://HOST:PORT``) where a TCP
    connection opens within ``timeout`` seconds; ``auto`` (Ray finds the cluster itself) is
    passed on. Checked before anything is written, since ``ray.init`` on an address where
    nothing answers retries for minutes."""
    if address == "auto":
        return
    rest = address[len("ray://"):] if address.startswith("ray://") else address
    host, sep, port = rest.rpartition(":")
    host = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536 \
            or any(c.isspace() or c in "/@" for c in host):
        raise ValueError(f"--ray {shown(address)} is invalid; allowed: HOST:PORT of a running "
                         "`ray start --head` (e.g. 127.0.0.1:6379), ray://HOST:PORT, auto, or "
                         "--ray alone for a local instance")
    try:
        with socket.create_connection((host, int(port)), timeout=timeout):
            pass
    except OSError as e:
        reason = e.strerror or type(e).__name__
        raise ValueError(f"--ray {address}: nothing answers at {host}:{port} within "
                         f"{timeout:g} s ({reason}); allowed: the address of a running "
                         "`ray start --head`") from None


def _probe(folder: str, token: str) -> str:
    """In a task: write ``token`` into ``folder`` and name the node."""
    path = Path(folder) / f".ray-probe-{token}"
    path.write_text(token)
    return socket.gethostname()


class RayBackend:
    """Submits runs as Ray tasks; :meth:`poll` reports finished ones."""

    def __init__(self, address: str | None, jobs: int | None, out: Path,
                 device: str | None = None) -> None:
        ray = _import_ray()
        self.ray = ray
        self._started = address is None
        if address is None:
            ray.init(num_cpus=jobs, include_dashboard=False, _node_ip_address="127.0.0.1",
                     logging_level="ERROR", log_to_driver=False)
        else:
            try:
                ray.init(address=address, logging_level="ERROR", log_to_driver=False)
            except (ConnectionError, ValueError, RuntimeError) as e:
                raise ValueError(f"--ray {address}: cannot join the Ray cluster ({e}); allowed: "
                                 "the address of a running `ray start --head`") from None
        cpus = int(ray.cluster_resources().get("CPU", 1))
        self.capacity = jobs or cpus
        self.description = f"Ray ({'local, ' if self._started else ''}{cpus} CPUs)"
        self.device = device
        self._task = ray.remote(num_cpus=1, max_retries=MAX_RETRIES)(run_blocking)
        self._refs: dict = {}
        self._check_shared(out)

    def _check_shared(self, out: Path) -> None:
        token = secrets.token_hex(8)
        try:
            node = self.ray.get(self.ray.remote(num_cpus=0)(_probe).remote(str(out), token))
        except Exception as e:  # the task's error (e.g. PermissionError) comes back wrapped
            self.close()
            raise ValueError(f"--out {out} is not writable from a Ray task ({type(e).__name__}); "
                             "allowed: a folder on a filesystem every Ray node shares, at the "
                             "same path") from None
        probe = out / f".ray-probe-{token}"
        seen = probe.is_file() and probe.read_text() == token
        probe.unlink(missing_ok=True)
        if not seen:
            self.close()
            raise ValueError(f"--out {out}: a Ray task on node {node} wrote into it but this "
                             "machine does not see the file; allowed: a folder on a "
                             "filesystem every Ray node shares, at the same path")

    def submit(self, job: Job) -> None:
        """Queue ``job`` as a task (one CPU, retried when its worker dies)."""
        self._refs[self._task.remote(job, self.device)] = job

    def poll(self) -> list[tuple[Job, int]]:
        """(job, exit code) of every task that ended since the last call."""
        if not self._refs:
            return []
        ready, _ = self.ray.wait(list(self._refs), num_returns=len(self._refs), timeout=0)
        ended = []
        for ref in ready:
            job = self._refs.pop(ref)
            try:
                code = int(self.ray.get(ref))
            except Exception:  # retries used up: report it as a failed job
                code = -1
            ended.append((job, code))
        return ended

    def close(self) -> None:
        """Cancel what is still queued; shut down the Ray instance this backend started."""
        for ref in list(self._refs):
            self.ray.cancel(ref, force=True)
        self._refs.clear()
        if self._started:
            self.ray.shutdown()
