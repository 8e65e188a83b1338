"""``colorsort-baseline``'s recipe flags, generated from the recipe's fields as ``lerobot-train``'s are.

Every field of a recipe section is a flag ``--<section>.<field>=<value>`` (``--training.steps=4000``,
``--demos.cameras=snapshot,wrist``, ``--policy.optimizer_lr=3e-4``), and every registered demonstrator
perturbation is one more of ``demos`` (``--demos.late_pick=10``). Values are spelt as on ``lerobot-train``'s
command line: ``true``/``false``, ``none`` (or ``null``), lists comma-separated, pairs ``NAME:VALUE``
(``--demos.train_mix=default:1,lighting:2``). The help of each flag is its field's documentation and the
recipe's value.
"""

from __future__ import annotations

import argparse
import re
import types
import typing
from dataclasses import fields
from typing import Any

from colorsort.data.perturbations import PERTURBATIONS
from colorsort.errors import ConfigError
from colorsort.training.recipes import SECTIONS, Recipe

DEST = "recipe:"  # argparse destinations of recipe flags start so


def field_docs(cls: type) -> dict[str, str]:
    """``name: text`` entries of a dataclass docstring's ``Attributes:`` section, joined into one line each."""
    doc = (cls.__doc__ or "").partition("Attributes:")[2]
    found: dict[str, str] = {}
    for match in re.finditer(r"^ {8}(\w+): (.*?)(?=^ {8}\w+: |\Z)", doc, re.S | re.M):
        found[match[1]] = " ".join(match[2].split())
    return found


def show(value: Any) -> str:
    """A value as a flag spells it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "none"
    if isinstance(value, tuple):
        return ",".join(":".join(map(show, v)) if isinstance(v, tuple) else show(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def parse(text: str, hint: Any, flag: str) -> Any:
    """``text`` as a value of type ``hint`` (int, float, str, bool, X | None, tuple[X, ...], tuple[X, Y])."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (types.UnionType, typing.Union) and type(None) in args:
        if text.lower() in ("none", "null"):
            return None
        (hint,) = [a for a in args if a is not type(None)]
        origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin is tuple and len(args) == 2 and args[1] is Ellipsis:
        return () if text.lower() in ("", "none") else tuple(parse(t, args[0], flag) for t in text.split(","))
    if origin is tuple:  # a pair: "A:B" (as in a list of pairs) or "A,B" (as shown alone)
        parts = text.split(":") if ":" in text else text.split(",")
        if len(parts) != len(args):
            raise ConfigError(f"{flag}: {text!r} is not {':'.join(a.__name__.upper() for a in args)}")
        return tuple(parse(p, a, flag) for p, a in zip(parts, args, strict=True))
    if hint is bool:
        if text.lower() not in ("true", "false"):
            raise ConfigError(f"{flag}: {text!r}: give true or false")
        return text.lower() == "true"
    try:
        return hint(text)
    except (TypeError, ValueError) as err:
        raise ConfigError(f"{flag}: {text!r} is not a valid {getattr(hint, '__name__', hint)}") from err


def settable(section: object) -> list[tuple[str, Any]]:
    """(field, type) of each field of a section a flag can set (perturbations have their own flags)."""
    hints = typing.get_type_hints(type(section))
    return [(f.name, hints[f.name]) for f in fields(section)  # type: ignore[arg-type]
            if f.init and f.name != "perturbations"]


def add_recipe_flags(parser: argparse.ArgumentParser, recipe: Recipe) -> None:
    """A group of flags per recipe section, each defaulting to the recipe's own value (left as None here)."""
    for section_name in SECTIONS:
        section = getattr(recipe, section_name)
        docs = field_docs(type(section))
        group = parser.add_argument_group(f"recipe {section_name} (--{section_name}.FIELD=VALUE)")
        for name, _ in settable(section):
            value = show(getattr(section, name))
            group.add_argument(f"--{section_name}.{name}", dest=f"{DEST}{section_name}.{name}", metavar="V",
                               help=f"{docs.get(name, '')} (recipe {recipe.name!r}: {value})".lstrip())
        if section_name == "demos":
            own = {p.name: p for p in recipe.demos.perturbations}
            for name, kind in PERTURBATIONS.items():
                value = own[name].text if name in own else "off"
                group.add_argument(f"--demos.{name}", dest=f"{DEST}demos.{name}", metavar=kind.metavar,
                                   help=f"perturbation: {kind.help} (recipe {recipe.name!r}: {value})")


def recipe_changes(args: argparse.Namespace, recipe: Recipe) -> dict[str, Any]:
    """The changes to ``recipe`` the flags in ``args`` ask for (``Recipe.override``'s keys and values)."""
    changes: dict[str, Any] = {}
    for dest, text in vars(args).items():
        if not dest.startswith(DEST) or text is None:
            continue
        key = dest.removeprefix(DEST)
        section_name, _, name = key.partition(".")
        value: Any
        if section_name == "demos" and name in PERTURBATIONS:
            value = PERTURBATIONS[name].parse(text)
        else:
            value = parse(text, dict(settable(getattr(recipe, section_name)))[name], f"--{key}")
        changes[key] = value
    return changes

