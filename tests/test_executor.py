"""runs/executor.py and cli/executor_options.py: a Monte Carlo over Iwan joint parameters
gives bitwise the same results serially, in a process pool and on a dask.distributed
LocalCluster of 2 workers (started by the sweep, and reached by its address); each
sample is also checked against the exact Iwan dissipation."""
import argparse
import sys
import warnings

import distributed
import numpy as np
import pytest

from cli.executor_options import add_executor_arguments, executor_from_args
from runs import executor as ex
from runs.executor import ExecutorSpec, run_sweep, task_seeds
from joints.describing import describing_function
from joints.iwan import IwanParameters, dissipation_per_cycle
from joints.jenkins import discretize, jenkins_update

N_SLIDERS = 60
N_STEPS = 240


def mc_sample(seed):
    """One Monte Carlo sample: random Iwan joint and slip amplitude, the exact
    describing function, and the steady hysteresis loop of a Jenkins bank."""
    rng = np.random.default_rng(seed)
    p = IwanParameters(chi=rng.uniform(-0.9, -0.1), K_T=10 ** rng.uniform(4, 7),
                       F_S=10 ** rng.uniform(1, 3), beta=rng.uniform(0.0, 5.0))
    A = rng.uniform(0.2, 0.9) * p.phi_max
    d = discretize(p, N_SLIDERS)
    u = A * np.sin(np.linspace(0.0, 4 * np.pi, 2 * N_STEPS + 1))
    anchor = np.zeros((1, N_SLIDERS))
    force = np.empty(u.size)
    for i, x in enumerate(u):
        F, _, anchor = jenkins_update(np.array([x]), anchor, d.stiffness, d.slip_limit)
        force[i] = F[0]
    u2, F2 = u[N_STEPS:], force[N_STEPS:]       # second (steady) cycle
    area = 0.5 * abs(np.dot(u2[:-1], F2[1:]) - np.dot(u2[1:], F2[:-1]))
    k_in, k_q = describing_function(p, A)
    return np.array([p.chi, p.K_T, p.F_S, p.beta, A, k_in, k_q, area,
                     dissipation_per_cycle(p, A)])


def mc_sample_scaled(seed, scale):
    return scale["factor"] * mc_sample(seed)


def failing(task):
    if task == 3:
        raise ZeroDivisionError(f"task {task} failed")
    return task


def bits(a):
    return np.asarray(a, dtype=np.float64).view(np.uint64)


@pytest.fixture(scope="module")
def seeds():
    return task_seeds(20240611, 12)


@pytest.fixture(scope="module")
def serial(seeds):
    return np.array(run_sweep(mc_sample, seeds, progress=False))


# ----------------------------------------------------------------- serial


def test_seeds_reproducible_and_independent(seeds):
    again = task_seeds(20240611, 12)
    draws = [np.random.default_rng(s).random(4) for s in seeds]
    assert all(np.array_equal(d, np.random.default_rng(s).random(4))
               for d, s in zip(draws, again))
    assert len({tuple(d) for d in draws}) == 12
    assert not np.array_equal(task_seeds(1, 1)[0].generate_state(4),
                              task_seeds(2, 1)[0].generate_state(4))


def test_serial_sweep_is_the_loop_and_the_samples_are_physical(serial, seeds, capsys):
    loop = np.array([mc_sample(s) for s in seeds])
    np.testing.assert_array_equal(bits(serial), bits(loop))
    # loop area of the 60-slider bank vs exact micro-slip dissipation (midpoint rule,
    # error ~ c/m_A^2 with m_A = n (A/phi_max)^(chi+1) >= 60*0.2 sliders slipping)
    np.testing.assert_allclose(serial[:, 7], serial[:, 8], rtol=0.03)
    # dissipation = pi A^2 k_quadrature (ARCHITECTURE sign convention)
    np.testing.assert_allclose(serial[:, 8], np.pi * serial[:, 4] ** 2 * serial[:, 6],
                               rtol=1e-10)
    order = []
    out = run_sweep(mc_sample, seeds[:3], desc="monte carlo",
                    on_result=lambda i, r: order.append(i))
    assert order == [0, 1, 2] and np.array_equal(np.array(out), serial[:3])
    assert "monte carlo" in capsys.readouterr().err


def test_shared_object_and_empty_sweep(serial, seeds):
    scaled = run_sweep(mc_sample_scaled, seeds[:4], shared={"factor": 2.0}, progress=False)
    np.testing.assert_array_equal(np.array(scaled), 2.0 * serial[:4])
    assert run_sweep(mc_sample, [], executor="processes", progress=False) == []


# ----------------------------------------------------------------- processes


def test_process_pool_bitwise_equal_to_serial(serial, seeds):
    done = []
    got = run_sweep(mc_sample, seeds, executor="processes", workers=2, chunksize=5,
                    progress=False, on_result=lambda i, r: done.append((i, r)))
    np.testing.assert_array_equal(bits(np.array(got)), bits(serial))
    assert sorted(i for i, _ in done) == list(range(12))
    assert all(np.array_equal(r, serial[i]) for i, r in done)
    scaled = run_sweep(mc_sample_scaled, seeds[:4], executor="processes", workers=2,
                       shared={"factor": 0.5}, progress=False)
    np.testing.assert_array_equal(np.array(scaled), 0.5 * serial[:4])


def test_task_errors_propagate():
    with pytest.raises(ZeroDivisionError, match="task 3"):
        run_sweep(failing, range(6), progress=False)
    with pytest.raises(ZeroDivisionError, match="task 3"):
        run_sweep(failing, range(6), executor="processes", workers=2, progress=False)
    with pytest.raises(ValueError, match="module-level"):
        run_sweep(lambda t: t, range(3), executor="processes", workers=2, progress=False)


# ----------------------------------------------------------------- dask


@pytest.fixture(scope="module")
def local_cluster():
    """Two worker processes on the loopback interface (any free port, no dashboard):
    dask and distributed are declared dependencies, so this must start (no skip)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Port .* is already in use")
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                           host="127.0.0.1", dashboard_address=None)
    yield cluster
    cluster.close()


def test_dask_cluster_started_by_the_sweep_bitwise_equal(serial, seeds, local_cluster, capsys):
    # the sweep starts (and closes) its own LocalCluster of 2 workers
    got = run_sweep(mc_sample, seeds, executor="dask", workers=2, chunksize=2,
                    desc="dask monte carlo")
    np.testing.assert_array_equal(bits(np.array(got)), bits(serial))
    assert "local dask cluster of 2 workers" in capsys.readouterr().err


def test_existing_dask_cluster_by_address(serial, seeds, local_cluster):
    address = local_cluster.scheduler_address
    assert address.startswith("tcp://")
    got = run_sweep(mc_sample, seeds, executor="dask", scheduler=address, chunksize=1,
                    progress=False)
    np.testing.assert_array_equal(bits(np.array(got)), bits(serial))
    scaled = run_sweep(mc_sample_scaled, seeds[:4], executor="dask", scheduler=address,
                       shared={"factor": 3.0}, progress=False)
    np.testing.assert_array_equal(np.array(scaled), 3.0 * serial[:4])
    with pytest.raises(ZeroDivisionError, match="task 3"):
        run_sweep(failing, range(6), executor="dask", scheduler=address, progress=False)
    # a connected client is used as is and stays open
    from distributed import Client

    with Client(address) as client:
        got = ExecutorSpec("dask", scheduler=client).run(mc_sample, seeds[:3], progress=False)
        np.testing.assert_array_equal(bits(np.array(got)), bits(serial[:3]))
        assert client.status == "running"


def test_unreachable_scheduler_is_one_line_error():
    with pytest.raises(ConnectionError, match="tcp://127.0.0.1:9: cannot connect"):
        run_sweep(mc_sample, [1], executor="dask", scheduler="tcp://127.0.0.1:9",
                  progress=False)


# ----------------------------------------------------------------- specs and CLI


@pytest.mark.parametrize("kwargs, message", [
    (dict(kind="threads"), "executor must be one of"),
    (dict(kind="processes", workers=0), "workers must be an integer >= 1"),
    (dict(kind="processes", workers=1.5), "workers must be an integer >= 1"),
    (dict(kind="processes", scheduler="tcp://h:1"), "needs the dask executor"),
    (dict(kind="dask", workers=2, scheduler="tcp://h:1"), "not both"),
    (dict(kind="dask", scheduler="my-cluster"), "scheduler must be an address"),
])
def test_spec_validation(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ExecutorSpec(**kwargs)


def test_spec_descriptions():
    assert ExecutorSpec().describe() == "serial"
    assert ExecutorSpec("processes", 3).describe() == "3 local processes"
    assert ExecutorSpec("dask", 2).describe() == "local dask cluster of 2 workers"
    assert ExecutorSpec("dask", scheduler="tcp://10.0.0.5:8786").describe() == \
        "dask cluster at tcp://10.0.0.5:8786"
    assert ExecutorSpec("dask", scheduler="cluster.json").scheduler == "cluster.json"
    assert ExecutorSpec("dask", scheduler="node7:8786").n_workers >= 1
    with pytest.raises(ValueError, match="chunksize"):
        run_sweep(mc_sample, [1], chunksize=0)


def parse(argv):
    parser = argparse.ArgumentParser(prog="iwanfe test", exit_on_error=False)
    add_executor_arguments(parser)
    return parser.parse_args(argv)


@pytest.mark.parametrize("argv, expected", [
    ([], ExecutorSpec("serial")),
    (["--workers", "2"], ExecutorSpec("dask", 2)),
    (["--scheduler", "tcp://10.0.0.5:8786"], ExecutorSpec("dask", scheduler="tcp://10.0.0.5:8786")),
    (["--executor", "processes", "--workers", "3"], ExecutorSpec("processes", 3)),
    (["--executor", "processes"], ExecutorSpec("processes")),
    (["--executor", "dask"], ExecutorSpec("dask")),
])
def test_cli_options(argv, expected, monkeypatch):
    # parsing only: the reachability check of --scheduler is tested in test_cli_validation
    monkeypatch.setattr(ExecutorSpec, "check", lambda self: self)
    assert executor_from_args(parse(argv)) == expected


@pytest.mark.parametrize("argv, message", [
    (["--scheduler", "tcp://h:1", "--workers", "2"], "not both"),
    (["--executor", "processes", "--scheduler", "tcp://h:1"], "needs the dask executor"),
    (["--executor", "serial", "--workers", "2"], "takes neither"),
    (["--scheduler", "somewhere"], "scheduler must be an address"),
])
def test_cli_bad_combinations(argv, message):
    with pytest.raises(ValueError, match=message):
        executor_from_args(parse(argv))


def test_cli_rejects_non_positive_workers(capsys):
    parser = argparse.ArgumentParser(prog="iwanfe test")
    add_executor_arguments(parser)
    for bad in ("0", "-1", "two"):
        with pytest.raises(SystemExit) as exc:
            parser.parse_args(["--workers", bad])
        assert exc.value.code == 2
    assert "--workers" in capsys.readouterr().err


def test_module_does_not_leak_environment():
    import os

    before = {k: os.environ.get(k) for k in ex._ONE_THREAD}
    run_sweep(failing, [0, 1], executor="processes", workers=1, progress=False)
    assert {k: os.environ.get(k) for k in ex._ONE_THREAD} == before
    assert "runs.executor" in sys.modules
