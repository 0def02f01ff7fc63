"""The runtime dependencies a lent many-core device lacks, and a check of them there.

The device (the ``nvidia-h200`` kind: 16 cores, CPython 3.12 on x86-64 Linux, no network)
has the Python packages of :data:`DEVICE_HAS`; whatever else gyropipe needs at run time
travels as wheels in ``.whl`` (``benchmarks/device_wheels.sh``, which calls this).

    python benchmarks/device_deps.py wheels   # here, in the project's venv: NAME==VERSION to carry
    python benchmarks/device_deps.py check    # there: each requirement, the version found

Both walk ``pyproject.toml``'s ``[project] dependencies`` and, through the installed
distributions' metadata, the requirements of each package that is carried (markers
evaluated for :data:`DEVICE_ENV`, no extras), stopping at a package the device has.
``wheels`` prints each package to carry once, at the version installed here (the one the
tests run with). ``check`` prints every requirement met or not by what Python finds
(``PYTHONPATH=/tmp/site:src`` there) and exits 1 if one is missing or out of its range.
"""

from __future__ import annotations

import sys
import tomllib
from importlib import metadata
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[1]
IMAGE = """
absl-py accelerate aiofiles aiohappyeyeballs aiohttp aiosignal annotated-doc anyio attrs botorch
build certifi charset-normalizer chex click cloudpickle cmake colorama contourpy coverage
cuda-bindings cuda-core cuda-pathfinder cuda-toolkit cupy-cuda13x cycler cython diffrax e3nn
einops equinox etils execnet filelock flatbuffers flax fonttools formulaic frozenlist fsspec
gpytorch grpcio h11 h5py hf-xet httpcore httpx huggingface-hub humanize hypothesis idna imageio
iniconfig interface-meta jax jax-cuda13-pjrt jax-cuda13-plugin jaxlib jaxtyping jinja2 joblib
kiwisolver lazy-loader lightning lightning-utilities linear-operator lineax llvmlite lxml
markdown markdown-it-py markupsafe matplotlib mdurl meson ml-dtypes mpi4py mpmath msgpack
multidict multipledispatch mypy-extensions nanobind narwhals networkx ninja numba numba-cuda
numpy numpyro nvidia-cublas nvidia-cuda-cupti nvidia-cuda-nvrtc nvidia-cuda-runtime
nvidia-cudnn-cu13 nvidia-cufft nvidia-cufile nvidia-curand nvidia-cusolver nvidia-cusparse
nvidia-cusparselt-cu13 nvidia-ml-py nvidia-nccl-cu13 nvidia-nvjitlink nvidia-nvshmem-cu13
nvidia-nvtx onnx onnx-ir onnxruntime onnxscript opencv-python-headless opt-einsum opt-einsum-fx
optax optimistix orbax-checkpoint packaging pandas pathspec patsy peft pillow pip pluggy
portalocker prometheus-client propcache protobuf psutil py-cpuinfo pyarrow pybind11 pygments
pyparsing pyproject-hooks pyre-extensions pytest pytest-benchmark pytest-cov pytest-mock
pytest-timeout pytest-xdist python-dateutil pytorch-lightning pyyaml regex requests rich
sacrebleu safetensors scikit-build-core scikit-image scikit-learn scipy seaborn
sentence-transformers sentencepiece setuptools shellingham simplejson six sortedcontainers
statsmodels sympy tabulate tensorboard tensorboard-data-server tensorstore threadpoolctl
tifffile tiktoken timm tokenizers toolz torch torch-geometric torchaudio torchdiffeq
torchmetrics torchvision tqdm transformers treescope triton typer typing-extensions
typing-inspect urllib3 uvloop wadler-lindig werkzeug wheel wrapt xarray xxhash yarl zipp
"""
DEVICE_HAS = frozenset(IMAGE.split())
"""The image's Python packages as the workplace last read them (2026-11-17), names
normalised; their versions are not known here (``check`` prints them there)."""
CARRIED_ANYWAY = frozenset({"typing-extensions"})
"""Held by the device but carried all the same: pydantic 2.14 needs typing-extensions ≥ 4.16,
and the device's version is not known here (it is pure Python, 50 kB)."""
NOT_IMPORTED = frozenset({"numpydoc"})
"""Declared but never imported at run time: allantools lists numpydoc (and with it Sphinx)."""
DEVICE_ENV = {
    "python_version": "3.12",
    "python_full_version": "3.12.3",
    "implementation_name": "cpython",
    "platform_python_implementation": "CPython",
    "sys_platform": "linux",
    "platform_system": "Linux",
    "platform_machine": "x86_64",
    "os_name": "posix",
    "extra": "",
}


def carried(name: str) -> bool:
    """Whether the package ``name`` (normalised) travels as a wheel."""
    return name not in NOT_IMPORTED and (name not in DEVICE_HAS or name in CARRIED_ANYWAY)


def requires(name: str) -> list[Requirement]:
    """The installed distribution ``name``'s requirements that hold on the device."""
    found = (Requirement(text) for text in metadata.requires(name) or ())
    return [r for r in found if r.marker is None or r.marker.evaluate(DEVICE_ENV)]


def requirements() -> dict[str, list[Requirement]]:
    """Each package needed (normalised name, in the order met) → the requirements naming it:
    gyropipe's own and those of every carried package."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    queue = [Requirement(text) for text in project["dependencies"]]
    found: dict[str, list[Requirement]] = {}
    while queue:
        requirement = queue.pop(0)
        name = canonicalize_name(requirement.name)
        if name in NOT_IMPORTED:
            continue
        if name not in found and carried(name):
            queue += requires(name)
        found.setdefault(name, []).append(requirement)
    return found


def check() -> int:
    """One line per package needed: the version found, whether it is carried, and each
    requirement on it that it fails; 1 if one is missing or out of range."""
    failed = 0
    for name, named in requirements().items():
        try:
            version = metadata.version(name)
        except metadata.PackageNotFoundError:
            version = None
        where = "carried" if carried(name) else "device"
        unmet = [str(r) for r in named if not (version and r.specifier.contains(version, True))]
        failed += bool(unmet)
        status = f"NOT MET: {', '.join(unmet)}" if unmet else "ok"
        print(f"{name:<24} {version or 'missing':<14} {where:<8} {status}")
    print(f"{failed} requirement(s) not met" if failed else "every requirement met")
    return 1 if failed else 0


def main() -> int:
    if sys.argv[1:] == ["wheels"]:
        for name in requirements():
            if carried(name):
                print(f"{name}=={metadata.version(name)}")
        return 0
    if sys.argv[1:] == ["check"]:
        return check()
    print(f"usage: {sys.argv[0]} wheels|check", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
