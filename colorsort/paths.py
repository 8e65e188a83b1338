"""Where the shipped MJCF assets live, in a source checkout and in an installed wheel alike."""

from importlib.resources import files
from pathlib import Path

ASSETS_DIR = Path(str(files("colorsort.assets")))


def asset_path(*parts: str) -> str:
    """Absolute path of a file under the assets folder, e.g. ``asset_path("irb140", "robot.xml")``."""
    path = ASSETS_DIR.joinpath(*parts)
    if not path.exists():
        raise FileNotFoundError(f"ColorSort asset not found: {path}")
    return str(path)
