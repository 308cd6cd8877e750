"""Hostile inputs (issue 36): mutations of the shipped examples of all four methods, each run through the
command line (``blastfsi.cli.main``), must be refused at validation: exit 2, the offending key named in a
short message, no traceback, nothing written, and nothing compiled (the compiler is replaced by a trap, so a
mutation that slipped through would fail loudly instead of running)."""
import math

import pytest
import tomli_w

import blastfsi.method
from blastfsi import cli
from blastfsi.api import example_data

# Examples whose every float (and list of floats) becomes NaN, +inf or -inf in turn: two per method.
SWEPT = ("plate1d-uniform", "tnt-free-air", "sod", "sedov-2d", "taylor-bar", "soil-column", "cfdmp-shock-tube",
         "he-slab-2d")
NON_FINITE = (math.nan, math.inf, -math.inf)


def _float_leaves(data: dict, prefix: str = ""):
    """(dotted key, value) of every float or list of floats outside arrays of tables."""
    for key, value in data.items():
        path = f"{prefix}{key}"
        if isinstance(value, dict):
            yield from _float_leaves(value, path + ".")
        elif isinstance(value, float) or (isinstance(value, list) and value and isinstance(value[0], float)):
            yield path, value


def _toml(value) -> str:
    return tomli_w.dumps({"v": value})[4:].strip()


def _non_finite_cases():
    cases = []
    for example in SWEPT:
        for k, (key, value) in enumerate(_float_leaves(example_data(example))):
            bad = NON_FINITE[k % 3]
            mutated = bad if isinstance(value, float) else [bad] + value[1:]
            cases.append(pytest.param(example, [f"{key}={_toml(mutated)}"], [key], id=f"{example}:{key}={bad}"))
    return cases


# (example, --set overrides, fragments the message must hold)
HANDWRITTEN = [
    # material constants outside their ranges (library entries through [materials.X])
    ("taylor-bar", ["materials.copper-ofhc.n=-0.5"], ["materials.copper-ofhc.n", ">= 0"]),
    ("taylor-bar", ["materials.copper-ofhc.A=nan"], ["materials.copper-ofhc.A"]),
    ("taylor-bar", ["materials.copper-ofhc.B=-1e6"], ["materials.copper-ofhc.B"]),
    ("taylor-bar", ["materials.copper-ofhc.m=0.0"], ["materials.copper-ofhc.m", "> 0"]),
    ("taylor-bar", ["materials.copper-ofhc.melt_temperature=200.0"], ["materials.copper-ofhc.melt_temperature"]),
    ("taylor-bar", ["materials.copper-ofhc.taylor_quinney=1.5"], ["materials.copper-ofhc.taylor_quinney"]),
    ("taylor-bar", ["materials.copper-ofhc.C0=0"], ["materials.copper-ofhc.C0"]),
    ("taylor-bar", ["materials.copper-ofhc.density=-8960.0"], ["materials.copper-ofhc.density"]),
    ("sod", ["materials.air.gamma=0.5"], ["materials.air.gamma", "> 1"]),
    ("sod", ["materials.air.gamma=1"], ["materials.air.gamma"]),
    ("sod", ["materials.air.specific_energy=-1.0"], ["materials.air.specific_energy"]),
    ("mpm-sod", ["materials.air.gamma=0.9"], ["materials.air.gamma"]),
    ("cfdmp-shock-tube", ["materials.air.gamma=0.5"], ["materials.air.gamma"]),
    ("tnt-free-air-axisym", ["materials.tnt.omega=0.0"], ["materials.tnt.omega", "> 0"]),
    ("tnt-free-air-axisym", ["materials.tnt.R1=-4.15"], ["materials.tnt.R1"]),
    ("tnt-free-air-axisym", ["materials.tnt.E0=0"], ["materials.tnt.E0"]),
    ("tnt-free-air-axisym", ["materials.tnt.detonation_velocity=1e9"], ["materials.tnt.detonation_velocity"]),
    ("concrete-spall", ["materials.concrete-25mpa.initial_tensile_damage=0.0"],
     ["materials.concrete-25mpa.initial_tensile_damage"]),
    ("concrete-spall", ["materials.concrete-25mpa.P_lock=1e6"], ["materials.concrete-25mpa.P_lock"]),
    ("concrete-spall", ["materials.concrete-25mpa.EFMIN=0.0"], ["materials.concrete-25mpa.EFMIN"]),
    ("soil-column", ["materials.soil-sec44.friction_angle=95.0"], ["materials.soil-sec44.friction_angle"]),
    ("soil-column", ["materials.soil-sec44.dilation_angle=30.0"], ["materials.soil-sec44.dilation_angle"]),
    ("vibrating-bar", ["materials.elastic-steel.poisson_ratio=0.5"], ["materials.elastic-steel.poisson_ratio"]),
    ("he-slab-2d", ["materials.concrete-48mpa.fc=-48e6"], ["materials.concrete-48mpa.fc"]),
    ("steel-plate-blast", ["materials.steel-rha.n=-1.0"], ["materials.steel-rha.n"]),
    ("steel-plate-blast", ["materials.tnt.omega=0.0"], ["materials.tnt.omega"]),
    ("sod", ["materials.air.gamma_typo=1.3"], ["materials.air", "gamma_typo"]),
    # overrides of materials the scenario does not use (typos), naming the materials in use
    ("sod", ["materials.steel-rha.A=1e9"], ["materials.steel-rha", "air"]),
    ("taylor-bar", ["materials.copper.A=9e7"], ["materials.copper", "copper-ofhc"]),
    ("cfdmp-shock-tube", ["materials.tnt.omega=0.3"], ["materials.tnt", "air"]),
    ("steel-plate-blast", ["materials.steel-4340.n=0.3"], ["materials.steel-4340", "steel-rha"]),
    ("tnt-free-air-axisym", ["materials.air2.gamma=1.3"], ["materials.air2"]),
    # tracers and gauges: non-finite or outside the domain
    ("taylor-bar", ["output.tracers=[[nan, 0.0]]"], ["output.tracers[0]"]),
    ("taylor-bar", ["output.tracers=[[0.0, inf]]"], ["output.tracers[0]"]),
    ("taylor-bar", ["output.tracers=[[10.0, 10.0]]"], ["output.tracers[0]", "outside"]),
    ("steel-plate-blast", ["output.tracers=[[nan, 0.105]]"], ["output.tracers[0]"]),
    ("steel-plate-blast", ["output.tracers=[[0.0, 5.0]]"], ["output.tracers[0]", "mpm_region"]),
    ("sod", ["output.gauges=[nan]"], ["output.gauges[0]"]),
    ("sedov-2d", ["output.gauges=[[0.5, inf]]"], ["output.gauges[0]"]),
    ("he-slab-2d", ["output.gauges=[[100.0, 100.0]]"], ["output.gauges[0]", "outside the domain"]),
    ("cfdmp-shock-tube", ["output.gauges=[50.0]"], ["output.gauges[0]"]),
    ("he-slab-2d", ["initial.center=[100.0, 0.0]"], ["initial.center"]),
    ("steel-plate-blast", ["initial.center=[0.0, -5.0]"], ["initial.center"]),
    # absurd values anywhere in the schema
    ("plate1d-uniform", ["gas.gamma=1.0"], ["gas.gamma"]),
    ("plate1d-uniform", ["gas.density=-1.225"], ["gas.density"]),
    ("sod", ["initial.left.density=0.0"], ["initial.left.density"]),
    ("sedov-2d", ["domain.upper=[1.0, 1e300]"], ["domain.upper[1]"]),
    ("soil-column", ["gravity=[0.0, nan]"], ["gravity[1]"]),
    ("soil-column", ["gravity=[0.0, -1e12]"], ["gravity"]),
    ("soil-column", ['bodies=[{lower = [nan, 0.0], upper = [0.5, 1.0], material = "soil-sec44"}]'],
     ["bodies[0].lower[0]"]),
    ("taylor-bar", ["impactor.velocity=-190.0"], ["impactor.velocity"]),
    ("he-slab-2d", ["mpm_region.upper=[100.0, 0.5]"], ["mpm_region"]),
    ("steel-plate-blast", ['numerics.shape="linear"'], ["numerics.shape", "1D only", "gimp"]),
    # structures, named as structures (not as the MPM method's bodies), against the MPM box
    ("he-slab-2d", ['structures=[{shape = "box", lower = [0.134, 0.15], upper = [0.154, 0.6], material = "concrete-48mpa"}]'],
     ["structures[0]", "leaves the MPM box (mpm_region)"]),
    ("he-slab-2d", ['structures=[{shape = "box", lower = [0.134, 0.15], upper = [0.154, 0.35], material = "concrete-48mpa"}, '
                    '{shape = "box", lower = [0.134, 0.3], upper = [0.154, 0.4], material = "concrete-48mpa"}]'],
     ["structures[0] and structures[1] overlap"]),
    ("he-slab-2d", ['structures=[{shape = "box", lower = [0.134], upper = [0.154], material = "concrete-48mpa"}]'],
     ["structures[0].lower", "2 coordinate(s)"]),
    ("sod", ["time.end=-1.0"], ["time.end"]),
    ("sod", ['grid.cells="many"'], ["grid.cells"]),
    ("sod", ["grid.cells=100.5"], ["grid.cells"]),
    ("sod", ['method="eulr"'], ["method"]),
    ("sod", ['name="../escape"'], ["name"]),
    ("tnt-free-air", ['charge.explosive="semtex"'], ["charge.explosive", "semtex"]),
    ("soil-column", ['bodies=[{lower = [0.0, 0.0], upper = [0.5, 2.0], material = "soil-sec44"}]'],
     ["bodies[0]", "leaves the grid"]),  # (found when the bodies are built: plain numbers, not np.float64)
    # resources: memory, members, outputs, remap time
    ("sedov-3d", ["grid.cells=5000"], ["grid.cells", "GiB", "numerics.allow_large"]),
    ("he-slab-3d", ["grid.cells=5000"], ["grid.cells", "GiB"]),
    ("taylor-bar", ["numerics.capacity=500000000"], ["numerics.capacity", "GiB", "numerics.allow_large"]),
    ("he-slab-2d", ["numerics.capacity=500000000"], ["numerics.capacity", "GiB"]),
    ("sedov-2d", ["domain.upper=[1.0, 1e5]"], ["grid.cells", "GiB"]),
    ("tnt-free-air", ["domain.length=1e5", "grid.cells=10000000"], ["grid.cells", "zones"]),
    ("plate1d-uniform", [f"sweep.beta_s={[float(k + 1) for k in range(300)]}",
                         f"sweep.overpressure={[1e4 * (k + 1) for k in range(300)]}"], ["sweep", "90000"]),
    ("plate1d-uniform", ["output.checkpoint_interval=1e-18"], ["output.checkpoint_interval"]),
    ("sedov-2d", ["output.checkpoint_interval=1e-9"], ["output.checkpoint_interval"]),
    ("tnt-free-air-axisym", ["initial.remap_time=10.0"], ["initial.remap_time"]),
    ("he-slab-2d", ["initial.remap_time=10.0"], ["initial.remap_time"]),
]


@pytest.fixture
def no_compilation(monkeypatch, tmp_path):
    """Work in an empty directory, and make compiling a time loop an error."""
    def trap(*args, **kwargs):
        raise AssertionError("a hostile input reached the compiler")

    monkeypatch.setattr(blastfsi.method, "compiled_advance", trap)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    return work


def _refused(argv, capsys, work, fragments):
    out = work / "res"
    code = cli.main([*argv, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err and len(err) < 4000, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    assert "np.float64" not in err, err
    assert list(work.iterdir()) == [], "a refused scenario wrote files"
    return err


@pytest.mark.parametrize("example, overrides, fragments", _non_finite_cases() + [
    pytest.param(*case, id=f"{case[0]}:{' '.join(case[1])[:60]}") for case in HANDWRITTEN])
def test_hostile_mutation_is_refused_naming_the_key(example, overrides, fragments, capsys, no_compilation):
    argv = ["run", "--example", example]
    for item in overrides:
        argv += ["--set", item]
    _refused(argv, capsys, no_compilation, fragments)


def test_there_are_at_least_100_mutations_over_all_methods():
    cases = _non_finite_cases()
    methods = {example_data(c.values[0]).get("method", "lagrangian1d") for c in cases}
    assert len(cases) + len(HANDWRITTEN) >= 100 and methods == {"lagrangian1d", "euler", "mpm", "cfdmp"}


@pytest.mark.parametrize("content, fragment", [
    (b"\x00\xff\xfe\x00binary", "not a text (UTF-8) file"),
    (("name = 'x'\nv = " + "[" * 5000 + "]" * 5000 + "\n").encode(), "nested deeper"),
    (("method = 'euler'\n" + "".join(f"k{k} = 1\n" for k in range(500))).encode(), "and "),
    (b"[time\nend = 1", "not valid TOML"),
])
def test_hostile_files_give_one_message(content, fragment, tmp_path, capsys, no_compilation):
    scenario = tmp_path / "hostile.toml"
    scenario.write_bytes(content)
    err = _refused(["run", str(scenario)], capsys, no_compilation, [fragment])
    if "k0" in err:  # 500 unknown keys: the listing is capped
        assert err.count("unknown key") <= 20 and "more" in err


def test_allow_large_lets_a_large_run_through_validation():
    """numerics.allow_large is the explicit way to insist: the memory check then passes (the run would go on)."""
    from blastfsi.scenario import parse, set_dotted

    data = set_dotted(example_data("sedov-3d"), "grid.cells", 5000)
    with pytest.raises(blastfsi.scenario.ScenarioError, match="numerics.allow_large"):
        parse(data)
    assert parse(set_dotted(data, "numerics.allow_large", True)).grid.cells == 5000


def test_every_library_constant_has_a_range_with_a_reason_and_lies_in_it():
    import dataclasses

    from blastfsi.materials import LIBRARY, lookup, ranges

    for name, entry in LIBRARY.items():
        declared = ranges.ranges(entry)
        numeric = {f.name for f in dataclasses.fields(entry)} - {"description", "sources"}
        assert set(declared) == numeric, (name, numeric - set(declared))
        assert all(r.why for r in declared.values()), name
        lookup(name)  # within its ranges (MaterialError otherwise)
