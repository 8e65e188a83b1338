"""ColorSort: a conveyor colour-sorting cell as a robosuite task, with expert, recorder and benchmark."""

from pathlib import Path

from setuptools import find_packages, setup

# robosuite 1.5.2 declares mink==0.0.5 (numpy<2), opencv-python and pynput, none of which it
# imports at run time; overrides.txt drops those pins so that the stack below resolves.
# See README "Install" for the uv command and the pip-only alternative.
INSTALL_REQUIRES = [
    "robosuite==1.5.2",
    "mujoco==3.9.0",
    "mink>=1.2,<1.3",
    "numpy>=2,<3",
    "opencv-python-headless>=4.11,<4.14",
    "lerobot[dataset,training,evaluation]>=0.6.1,<0.7",
    "draccus>=0.11.6,<0.12",  # the commands' typed configs (cli/config_args.py), as LeRobot's; lerobot pins it too
    "mergedeep>=1.3.4,<2",  # config_args.py merges a --config_path file under the command line with it
    # imported directly (weights, tables, the recorder's parquet): lerobot's own ranges
    "torch>=2.7,<2.12",
    "safetensors>=0.4.3,<1",
    "pyarrow>=21,<30",
    "gymnasium>=1.0,<2",
    # robosuite.wrappers imports h5py (DataCollectionWrapper) for every wrapper:
    "h5py>=3.10,<4",
    "ruckig>=0.19,<0.20",
    "tqdm>=4.66,<5",
    "av>=15,<16",
    # --executor ray: collection and evaluation on a Ray cluster (a local one, or one that spans a SLURM job)
    "ray>=2.52,<3",  # 2.52: token authentication (`ray get-auth-token`)
    # colorsort-baseline plots success against the number of demos and training time:
    "matplotlib>=3.8,<4",
    # robosuite's real run-time needs, for `pip install --no-deps robosuite`:
    "numba>=0.59",
    "scipy>=1.11",
    "Pillow>=10",
    "termcolor>=2.4",
    "qpsolvers[daqp,quadprog]>=4.3.1",
]

EXTRAS_REQUIRE = {
    # playwright drives a system Chromium (Debian's `chromium`) in the report page's browser test; it downloads
    # no browser of its own unless `playwright install` is run
    "dev": ["pytest>=8", "build>=1.2", "ruff>=0.17.6,<0.18", "mypy>=2.4,<2.5", "playwright>=1.50,<2",
            "pytest-xdist>=3.6,<4"],
    # lerobot-dataset-viz (Rerun) on ColorSort's datasets
    "viz": ["lerobot[viz]>=0.6.1,<0.7"],
    # LeRobot's diffusion policy (diffusers), e.g. lerobot-train --policy.type=diffusion
    "diffusion": ["lerobot[diffusion]>=0.6.1,<0.7"],
    # the batched cell on MuJoCo Warp (colorsort.batched, colorsort-eval --backend warp): a pair that compiles and
    # steps the cell with MuJoCo 3.9 (docs/stack.md); 3.12 needs MuJoCo 3.11, which robosuite 1.5.2 does not run on
    "gpu": ["mujoco-warp==3.11.0", "warp-lang==1.19.0"],
}

setup(
    name="colorsort",
    version="0.1.0",
    description=(
        "An ABB IRB 140 with a vacuum cup sorting coloured boxes off a conveyor: "
        "a robosuite task, scripted expert, LeRobot demo recorder and benchmark."
    ),
    long_description=Path(__file__).with_name("README.md").read_text(encoding="utf-8")
    if Path(__file__).with_name("README.md").exists()
    else "",
    long_description_content_type="text/markdown",
    python_requires=">=3.12",
    # The top-level assets/ folder ships inside the wheel as the package colorsort.assets.
    packages=find_packages(include=["colorsort", "colorsort.*"]) + ["colorsort.assets"],
    package_dir={"colorsort.assets": "assets"},
    package_data={"colorsort.assets": ["*.md", "**/*.xml", "**/*.md", "**/*.json", "**/*.stl", "**/*.png"]},
    install_requires=INSTALL_REQUIRES,
    extras_require=EXTRAS_REQUIRE,
    entry_points={"console_scripts": [
        "colorsort-sort=colorsort.cli.sort:main",
        "colorsort-collect=colorsort.cli.collect:main",
        "colorsort-replay=colorsort.cli.replay:main",
        "colorsort-eval=colorsort.cli.eval:main",
        "colorsort-slurm=colorsort.cli.slurm:main",
        "colorsort-baseline=colorsort.cli.baseline:main",
        "colorsort-analyze=colorsort.cli.analyze:main",
        "colorsort-takeover=colorsort.cli.takeover:main",
    ]},
)
