"""The distributed engines a design sweep could run on (:mod:`jaxnet.design.sweep`), side by side: Dask's
distributed scheduler and Ray, on a local cluster of worker processes.

For each engine installed in this interpreter (the other is left out, said so), it prints:

* the time to start a local cluster of ``--workers`` worker processes (one thread each) and connect a client
  to it, until every worker is up;
* the time until each worker has imported jaxnet (what a sweep's first task pays before it builds anything);
* the round-trip time of one trivial task (submitted and waited for, one after the other: the latency a
  design pays on top of its solve) and the time per task of ``--tasks`` trivial tasks submitted at once
  and collected as they complete (the throughput overhead);
* the processes the cluster runs (descendants of this one) and their resident memory, after the tasks (with
  jaxnet imported in the workers where it is installed);
* the installed size of the engine's package.

Ray is not a dependency of jaxnet; measure it in a virtual environment of its own, e.g.
``python -m venv /tmp/rayenv && /tmp/rayenv/bin/pip install ray`` then
``/tmp/rayenv/bin/python validation/cluster_engines.py --engine ray`` (jaxnet's import is then skipped
unless jaxnet is installed there too).

Run: ``python validation/cluster_engines.py [--workers 2] [--tasks 200] [--engine dask|ray|all]``.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import pathlib
import time


def _trivial(i):
    return i + 1


def _import_jaxnet(_=None):
    """Import jaxnet in the worker; its process id (which worker answered)."""
    import jaxnet  # noqa: F401

    return os.getpid()


def _descendants():
    """(number, resident memory MB) of this process's descendant processes (Linux /proc): what a cluster
    started."""
    parents = {}
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
            parents[int(stat.parent.name)] = int(fields[1])
        except (OSError, ValueError, IndexError):
            continue
    found, frontier = set(), {os.getpid()}
    while frontier:
        frontier = {pid for pid, parent in parents.items() if parent in frontier} - found
        found |= frontier
    rss = 0
    for pid in found:
        try:
            rss += int(pathlib.Path(f"/proc/{pid}/statm").read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")
        except (OSError, ValueError, IndexError):
            continue
    return len(found), rss / 1e6


def _package_size(name):
    """Installed size (MB) of a package's directory."""
    spec = importlib.util.find_spec(name)
    root = pathlib.Path(spec.origin).parent
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file()) / 1e6


def measure_dask(workers, tasks, with_jaxnet):
    from distributed import Client, LocalCluster, as_completed

    start = time.perf_counter()
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    client.wait_for_workers(workers)
    started = time.perf_counter() - start
    imported = None
    if with_jaxnet:
        start = time.perf_counter()
        client.run(_import_jaxnet)  # on every worker
        imported = time.perf_counter() - start
    client.submit(_trivial, -1, pure=False).result()  # warm
    start = time.perf_counter()
    for i in range(50):
        client.submit(_trivial, i, pure=False).result()
    latency = (time.perf_counter() - start) / 50
    start = time.perf_counter()
    futures = [client.submit(_trivial, i, pure=False) for i in range(tasks)]
    for _ in as_completed(futures):
        pass
    throughput = (time.perf_counter() - start) / tasks
    processes = _descendants()
    start = time.perf_counter()
    client.close()
    cluster.close()
    closed = time.perf_counter() - start
    size = _package_size("distributed") + _package_size("dask")
    return started, imported, latency, throughput, closed, processes, size


def measure_ray(workers, tasks, with_jaxnet):
    import ray

    start = time.perf_counter()
    ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    trivial = ray.remote(num_cpus=1)(_trivial)
    # a local Ray starts its worker processes on demand: time until both have answered a task
    pids = set()
    while len(pids) < workers:
        pids |= set(ray.get([ray.remote(num_cpus=1)(lambda _: os.getpid()).remote(i) for i in range(workers)]))
    started = time.perf_counter() - start
    imported = None
    if with_jaxnet:
        start = time.perf_counter()
        ray.get([ray.remote(num_cpus=1)(_import_jaxnet).remote(i) for i in range(workers)])
        imported = time.perf_counter() - start
    ray.get(trivial.remote(-1))
    start = time.perf_counter()
    for i in range(50):
        ray.get(trivial.remote(i))
    latency = (time.perf_counter() - start) / 50
    start = time.perf_counter()
    pending = [trivial.remote(i) for i in range(tasks)]
    while pending:
        _, pending = ray.wait(pending, num_returns=1)
    throughput = (time.perf_counter() - start) / tasks
    processes = _descendants()
    start = time.perf_counter()
    ray.shutdown()
    closed = time.perf_counter() - start
    return started, imported, latency, throughput, closed, processes, _package_size("ray")


ENGINES = {"dask": ("distributed", measure_dask), "ray": ("ray", measure_ray)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--tasks", type=int, default=200)
    parser.add_argument("--engine", choices=[*ENGINES, "all"], default="all")
    args = parser.parse_args(argv)
    with_jaxnet = importlib.util.find_spec("jaxnet") is not None
    print(f"{args.workers} worker processes, one thread each; {args.tasks} trivial tasks; "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}"
          f"{'' if with_jaxnet else '; jaxnet not installed here: its import not timed'}")
    print(f"{'engine':8s} {'start (s)':>10s} {'import jaxnet (s)':>18s} {'round trip (ms)':>16s} "
          f"{'per task, batch (ms)':>21s} {'close (s)':>10s} {'processes':>10s} {'their RSS (MB)':>15s} "
          f"{'installed (MB)':>15s}")
    for name, (module, measure) in ENGINES.items():
        if args.engine not in (name, "all"):
            continue
        if importlib.util.find_spec(module) is None:
            print(f"{name:8s} not installed in this interpreter")
            continue
        started, imported, latency, throughput, closed, (processes, rss), size = measure(args.workers, args.tasks,
                                                                                          with_jaxnet)
        imported = "-" if imported is None else f"{imported:.2f}"
        print(f"{name:8s} {started:10.2f} {imported:>18s} {1e3 * latency:16.2f} {1e3 * throughput:21.2f} "
              f"{closed:10.2f} {processes:10d} {rss:15.0f} {size:15.1f}")


if __name__ == "__main__":
    main()
