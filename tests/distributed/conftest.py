"""A local Ray cluster for the distributed tests: 2 CPUs, loopback only, started once and stopped at the end."""

from __future__ import annotations

import os

import pytest

# Before ray is imported anywhere: a local instance then binds 127.0.0.1 only (no network address).
os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"
# Ray's workers at the test run's own priority (Ray lowers them by 15 by default; on a shared machine
# that starves them).
os.environ.setdefault("RAY_worker_niceness", "0")


@pytest.fixture(scope="session")
def ray_cluster():
    """The ``ray`` module, connected to a fresh local 2-CPU cluster (its address: ``ray_cluster.address``)."""
    import ray

    for attempt in range(3):  # Ray gives its raylet a fixed 30 s to register: a heavily loaded machine may miss it
        try:
            ray.init(num_cpus=2, include_dashboard=False)
            break
        except Exception as e:  # noqa: BLE001 - ray raises a bare Exception for this
            ray.shutdown()
            if "timed out during startup" not in str(e) or attempt == 2:
                raise
    try:
        assert ray.get_runtime_context().gcs_address.startswith("127.0.0.1:")
        yield ray
    finally:
        ray.shutdown()
