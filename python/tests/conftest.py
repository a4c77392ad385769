"""Fixtures shared by the Dask tests: a real distributed.LocalCluster of two worker processes,
bound to loopback only (scheduler, workers and dashboard), one per test module."""

import pytest


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                       dashboard_address="127.0.0.1:0", memory_limit="1GiB", silence_logs=40)
    c = distributed.Client(cluster, timeout=60)
    yield c
    c.close()
    cluster.close()
