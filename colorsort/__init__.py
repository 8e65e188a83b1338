"""ColorSort: an ABB IRB 140 with a vacuum cup sorts coloured boxes off a conveyor.

Importing the package registers the ``IRB140`` robot, the ``SuctionGripper`` and the
``ColorSort`` task with robosuite, so that ``suite.make("ColorSort", robots="IRB140")`` works,
and the Gymnasium ids ``colorsort/ColorSort-v0`` and one per benchmark variant
(``colorsort.variants``), so that ``gym.make("colorsort/ColorSort-v0")`` works.
"""

from colorsort.cell.rendering import ensure_gl_backend, gl_error, is_gl_failure
from colorsort.logs import quiet_robosuite_startup

ensure_gl_backend()  # before robosuite imports mujoco's renderer
quiet_robosuite_startup()  # before robosuite logs its import-time notices

try:
    from colorsort.cell import models  # registers IRB140 and SuctionGripper
    from colorsort.envs.robosuite_task import ColorSort  # registers the task
except Exception as error:  # robosuite loads its GL context module at import time
    if is_gl_failure(error):
        raise gl_error(error) from error
    raise

from colorsort.envs.gym_env import register_envs  # noqa: E402

register_envs()

__all__ = ["ColorSort", "models"]
