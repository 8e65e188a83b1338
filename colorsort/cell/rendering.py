"""Headless rendering: pick a GL backend, fail with a useful message when none loads."""

from __future__ import annotations

import os
import sys

GL_HELP = (
    "MuJoCo could not create an OpenGL context for off-screen rendering (MUJOCO_GL={backend!r}): {error}\n"
    "ColorSort renders headless with MUJOCO_GL=egl (Mesa's software EGL works without a GPU; on Debian/Ubuntu: "
    "apt-get install libegl1 libgl1-mesa-dri) or MUJOCO_GL=osmesa (apt-get install libosmesa6). "
    "To run without images, pass has_offscreen_renderer=False and use_camera_obs=False."
)


FORK_HELP = (
    "This process was forked from one that had already rendered with EGL (MUJOCO_GL=egl). "
    "An EGL display does not survive fork(): rendering here would hang. Start worker processes "
    "with the 'forkserver' or 'spawn' multiprocessing context (e.g. gym.make_vec(..., "
    "vector_kwargs={'context': 'forkserver'})), or fork them before the parent renders anything."
)
_EGL_MODULES = ("mujoco.egl", "robosuite.renderers.context.egl_context")
_egl_inherited = False  # set in a child forked from a process with an initialised EGL display


def _egl_display_initialised() -> bool:
    return any(getattr(sys.modules.get(name), "EGL_DISPLAY", None) is not None for name in _EGL_MODULES)


def _note_fork() -> None:
    global _egl_inherited
    _egl_inherited = _egl_inherited or _egl_display_initialised()


os.register_at_fork(after_in_child=_note_fork)


def ensure_gl_backend() -> None:
    """Default ``MUJOCO_GL`` to ``egl`` (headless) unless the user chose a backend."""
    os.environ.setdefault("MUJOCO_GL", "egl")


def is_gl_failure(error: BaseException) -> bool:
    """Whether an exception was raised inside an OpenGL binding or MuJoCo's GL context code."""
    tb = error.__traceback__
    while tb is not None:
        filename = tb.tb_frame.f_code.co_filename.replace("\\", "/")
        if any(part in filename for part in ("/OpenGL/", "/mujoco/egl/", "/mujoco/osmesa/", "_context")):
            return True
        tb = tb.tb_next
    return False


LOADED_FIRST = (
    "\nMuJoCo loaded its {loaded!r} backend before MUJOCO_GL was {backend!r}: it was imported before colorsort, "
    "which sets the headless default. Import colorsort before mujoco (and robosuite), or set MUJOCO_GL in the shell."
)


def loaded_backend() -> str | None:
    """The GL backend MuJoCo's renderer loaded when it was imported (``egl``, ``osmesa``, ``glfw``...); None before."""
    module = sys.modules.get("mujoco.rendering.classic.gl_context")
    context = getattr(module, "GLContext", None)
    return None if context is None else str(context.__module__).rsplit(".", 1)[-1]


def gl_error(error: BaseException) -> RuntimeError:
    """A ``RuntimeError`` that explains how to get a GL backend, wrapping ``error``; it names the backend MuJoCo
    loaded, and says so where that is not the one ``MUJOCO_GL`` asks for now."""
    backend, loaded = os.environ.get("MUJOCO_GL"), loaded_backend()
    text = GL_HELP.format(backend=backend, error=error)
    if loaded and loaded != (backend or "").lower():
        text += LOADED_FIRST.format(loaded=loaded, backend=backend)
    return RuntimeError(text)


def check_gl() -> None:
    """Render one pixel with MuJoCo; raise ``RuntimeError`` with set-up advice if that fails.

    Also raises ``RuntimeError`` (instead of hanging) in a process forked from one that had
    already rendered with EGL.
    """
    if _egl_inherited:
        raise RuntimeError(FORK_HELP)
    try:
        import mujoco

        model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
        with mujoco.Renderer(model, 8, 8) as renderer:
            renderer.update_scene(mujoco.MjData(model))
            renderer.render()
    except Exception as error:  # the backends raise ImportError, AttributeError, RuntimeError, mujoco.FatalError
        raise gl_error(error) from error
