"""The package's errors: typed, still the built-in kinds callers catch, and one exit status each for every CLI."""

import pytest

from colorsort.cli.run import guarded
from colorsort.config import make_config
from colorsort.errors import (
    ActionError,
    ColorSortError,
    ConfigError,
    DataConflictError,
    DataExistsError,
    StageError,
    exit_code,
)


@pytest.mark.parametrize("err,code", [
    (ConfigError("x"), 2), (ActionError("x"), 2), (DataConflictError("x"), 2), (DataExistsError("x"), 2),
    (StageError("x"), 1), (ValueError("x"), 2), (RuntimeError("x"), 1), (KeyboardInterrupt(), 130),
])
def test_each_error_has_one_exit_status(err, code):
    assert exit_code(err) == code


def test_errors_are_the_built_in_kinds_callers_already_catch():
    assert issubclass(ConfigError, ValueError) and issubclass(DataExistsError, FileExistsError)
    assert issubclass(StageError, RuntimeError) and issubclass(DataConflictError, ColorSortError)
    with pytest.raises(ConfigError, match="Valid presets"):
        make_config("turbo")


def test_a_guarded_main_prints_one_line_and_returns_the_status(capsys):
    def main_raising(err):
        @guarded("colorsort-x")
        def main(argv=None):
            raise err
        return main

    assert main_raising(ConfigError("bad value; valid: a, b"))([]) == 2
    assert capsys.readouterr().err == "colorsort-x: error: bad value; valid: a, b\n"
    assert main_raising(StageError("stage failed"))([]) == 1
    assert capsys.readouterr().err == "colorsort-x: stage failed\n"
    assert main_raising(KeyboardInterrupt())([]) == 130
    with pytest.raises(ZeroDivisionError):  # a bug is not an error of the user's: its traceback stays
        main_raising(ZeroDivisionError())([])


@pytest.mark.parametrize("lookup, valid_one", [
    (lambda: __import__("colorsort.variants", fromlist=["x"]).get_variant("hard"), "default"),
    (lambda: __import__("colorsort.training.recipes", fromlist=["x"]).get_recipe("big"), "camera-snapshot-touch-dr"),
    (lambda: __import__("colorsort.shifts", fromlist=["x"]).parse_shifts("bogus:1"), "box-size"),
    (lambda: make_config("turbo"), "tracking-fast"),
    (lambda: __import__("colorsort.robots", fromlist=["x"]).checked_robot("Sawyer", "SuctionGripper"), "IRB140"),
    (lambda: __import__("colorsort.data.perturbations", fromlist=["x"]).parse("late_drop", "3"), "late_pass"),
])
def test_a_name_looked_up_and_not_there_lists_every_valid_one(lookup, valid_one):
    """As mink's ``InvalidFrame``: ``UnknownName`` (a ``ConfigError``, so a ``ValueError``) carries and names them."""
    from colorsort.errors import UnknownName

    with pytest.raises(UnknownName) as caught:
        lookup()
    assert valid_one in caught.value.valid and repr(valid_one) in str(caught.value)
    assert isinstance(caught.value, ValueError)
