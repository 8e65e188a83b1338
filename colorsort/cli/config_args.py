"""A command's configuration is its command line: a dataclass parsed by draccus, as LeRobot's commands are.

Every field of the command's dataclass is a flag, a nested dataclass's fields are ``--group.field=value``,
``--config_path FILE`` reads any of them from a YAML or JSON file (the command line wins), and ``--help`` shows
each field with the comment beside it in the source and its default. A field whose type is a
``draccus.ChoiceRegistry`` picks its kind with ``--group.type=NAME`` (``--policy.type=diffusion``).

On top of draccus's own spelling (YAML values: ``--cameras=[scene,wrist]``, ``--resume=true``), the spellings
ColorSort's commands have always accepted keep working, so scripts written against them run unchanged:

- ``--kebab-case`` names for ``snake_case`` fields, and a value after a space (``--episodes 3``);
- a bool field as a bare switch (``--resume``) and a command's renamed flags (``--no-turn``, ``--report DIR``);
- list and pair values comma-separated (``--cameras scene,wrist``, ``--demos.train_mix=default:1,lighting:2``),
  ``none`` for an empty list or an unset option, and a list flag given twice adds to it (``--shift a:1 --shift b:2``);
- a field's own spelling where it has one (``--image-size 96x128``);
- member flags: one flag per entry of a registry that adds that entry to a list field (``--late-pass=100`` is
  ``--perturbations=[late_pass:100]``, merged with the entries already set by name).

Errors exit 2 with one line: argparse's for unknown flags, the field's own ``ConfigError`` for a bad value.

Only draccus's and argparse's public API: the spellings above become draccus's, and draccus parses them over one
config file, the defaults (a recipe's) with the ``--config_path`` file over them; ``--help`` is the parser's
``format_help`` with the defaults set.
"""

from __future__ import annotations

import argparse
import functools
import json
import re
import tempfile
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields, is_dataclass
from pathlib import Path
from typing import Any

import draccus
import draccus.argparsing
import mergedeep
from draccus.help_formatter import SimpleHelpFormatter
from draccus.utils import CONFIG_ARG, ParsingError

from colorsort.errors import ConfigError


@dataclass(frozen=True)
class Spelling:
    """How a command's flags may also be written.

    Attributes:
        renamed: an old flag (``--no-turn``) -> the flag and value it stands for (``--turn_to_box=false``), or the
            flag alone (``--report`` -> ``--report.dir``) when it takes the value given.
        values: a field's path -> a function from its text to its value (``image_size`` -> ``parse_image_size``).
        members: a member flag's path (``late_pass``) -> (the list field it adds to, a function from its text to
            the entry; every entry has a ``name``, the key entries are merged by).
        joined: text fields holding a comma-separated list (``shift``): given twice, the values join, as a list
            field's do (``--shift a:1 --shift b:train`` is ``--shift=a:1,b:train``), never the last alone.
    """

    renamed: Mapping[str, str] = types.MappingProxyType({})
    values: Mapping[str, Callable[[str], Any]] = types.MappingProxyType({})
    members: Mapping[str, tuple[str, Callable[[str], Any]]] = types.MappingProxyType({})
    joined: frozenset[str] = frozenset()


# draccus's metavar of a tuple[X, ...], "str [str, ...]", and the spaces after it in an option's line
_LIST_METAVAR = re.compile(r"((?:\w+ )*\w+) \[\1, \.\.\.\]( {2,})?")


def parse_config[T](cls: type[T], argv: Sequence[str], *, prog: str, description: str | None = None,
                    defaults: T | None = None, spelling: Spelling = Spelling(), epilog: str | None = None) -> T:
    """``argv`` as an instance of ``cls`` (``defaults``' values where a flag is not given); ``--help`` prints and
    exits 0; a bad flag exits 2; a bad value raises the ``ConfigError`` of the field that refused it.

    draccus parses the flags over one config file: ``defaults`` encoded, under the ``--config_path`` file given."""
    typed: dict[str, str] = {}
    args = respell(cls, defaults, list(argv), spelling, typed)
    given_file = [a.partition("=")[2] for a in args if a.startswith(f"--{CONFIG_ARG}=")]
    args = [a for a in args if not a.startswith(f"--{CONFIG_ARG}=")]
    with tempfile.TemporaryDirectory(prefix="colorsort-config-") as tmp:
        layered = Path(tmp) / "config.json"  # JSON: YAML would read 1e-05 as text
        layered.write_text(json.dumps(layered_defaults(defaults, given_file[-1] if given_file else None, args)))
        parser = draccus.argparsing.ArgumentParser(
            cls, config_path=layered, prog=prog, description=description, epilog=epilog,
            formatter_class=typing.cast(type[argparse.HelpFormatter],
                                        functools.partial(SimpleHelpFormatter, max_help_position=32, width=118)))
        if "--help" in args or "-h" in args:
            print_help(parser.parser, defaults if defaults is not None else cls())
        try:
            return parser.parse_args(args)
        except ParsingError as err:
            reason = _reason(err)
            for path, old in typed.items():  # name the flag as the user wrote it when its field refused the value
                if f"{path.rpartition('.')[2]}=" in str(reason):
                    raise ConfigError(f"{old} (--{path}): {reason}") from err
            raise reason from err


def layered_defaults(defaults: Any, config_path: str | None, args: Sequence[str]) -> dict:
    """``defaults`` encoded, the ``config_path`` file's values over them; a choice field (``policy``) whose kind the
    file or ``args`` change (``--policy.type=diffusion``) keeps none of the default kind's values."""
    base = draccus.encode(defaults) if defaults is not None else {}
    from_file: dict = {}
    if config_path is not None:
        with open(config_path, encoding="utf-8") as f:
            from_file = draccus.cfgparsing.load_config(f, file=config_path) or {}
    for key, value in list(base.items()):
        if not (isinstance(value, dict) and "type" in value):
            continue
        in_file = from_file.get(key, {}).get("type") if isinstance(from_file.get(key), dict) else None
        chosen = _choice(args, key) or in_file
        if chosen is not None and chosen != value["type"]:
            base[key] = {}
    return mergedeep.merge({}, base, from_file)


def print_help(parser: argparse.ArgumentParser, defaults: Any) -> None:
    """``--help``: each flag with its default as a flag spells it (nested ones too), a list's values as the flags
    take them (``str,str,...``, not draccus's ``str [str, ...]``), and without draccus's per-group config-file
    flags (``--report`` is ``--report.dir`` here; ``--config_path`` reads a file); exits 0."""
    parser.set_defaults(**{path: shown(value) for path, value in flattened(defaults)})
    text = parser.format_help()
    groups = re.findall(r"--(\S+) str +Config file for ", text)
    text = "\n".join(line for line in text.splitlines() if "Config file for " not in line)
    for group in groups:
        text = text.replace(f" [--{group} str]", "")
    print(_LIST_METAVAR.sub(_comma_metavar, text))
    raise SystemExit(0)


def _comma_metavar(match: re.Match) -> str:
    """``str,str,...`` for draccus's ``str [str, ...]`` (``str:float,...`` for a list of pairs), padded to keep the
    help column where the longer text had it."""
    entry = ":".join(match[1].split())
    spelt = f"{entry},{entry},..."
    return spelt + " " * (len(match[0]) - len(spelt)) if match[2] else spelt


def flattened(obj: Any, prefix: str = "") -> list[tuple[str, Any]]:
    """``(path, value)`` of every field of the dataclass ``obj``, nested ones as ``group.field``."""
    found: list[tuple[str, Any]] = []
    for f in fields(obj):
        value, path = getattr(obj, f.name), f"{prefix}{f.name}"
        nested = is_dataclass(value) and not isinstance(value, type)
        found += flattened(value, f"{path}.") if nested else [(path, value)]
    return found


def _reason(err: BaseException) -> ConfigError:
    """The ``ConfigError`` a field raised under draccus's wrapping, else draccus's message as one."""
    cause: BaseException | None = err
    while cause is not None:
        if isinstance(cause, ConfigError):
            return cause
        cause = cause.__cause__ or cause.__context__
    return ConfigError(" ".join(str(err).split()))


def renamed(name: str, has_value: str, text: str, spelling: Spelling,
            typed: dict[str, str] | None) -> tuple[str, str, str]:
    """A flag's (name, "=" or "", value text) after its old name is translated (``Spelling.renamed``): an old switch
    (``--overwrite``) gets the value it stands for; ``typed`` records the old name under the new path."""
    new = spelling.renamed.get(f"--{name}")
    if not new:
        return name, has_value, text
    old, (name, has_fixed, fixed) = name, new[2:].partition("=")
    if typed is not None:
        typed[name] = f"--{old}"
    if has_fixed and has_value and fixed != "true":
        raise ConfigError(f"--{old} takes no value: it stands for {new}")
    if has_fixed and not has_value:  # a switch: --overwrite is --report.overwrite=true, and =false says no
        has_value, text = "=", fixed
    return name, has_value, text


def respell(cls: type, defaults: Any, argv: list[str], spelling: Spelling,
            typed: dict[str, str] | None = None) -> list[str]:
    """``argv`` in draccus's spelling: every flag ``--path=yaml``, the older spellings translated (module doc);
    ``typed`` gets each renamed flag's new path and its old name as given."""
    out: list[str] = []
    lists: dict[str, list] = {}  # list fields given, or added to by member flags: their entries so far
    joined: dict[str, list[str]] = {}  # comma-separated text fields given: their values so far
    i = 0
    while i < len(argv):
        token = argv[i]
        i += 1
        if not token.startswith("--") or token in ("--help", "-h"):
            out.append(token)
            continue
        name, has_value, text = renamed(*token[2:].partition("="), spelling, typed)
        path = name if name == CONFIG_ARG else ".".join(p.replace("-", "_") for p in name.split("."))
        hint = field_hint(cls, defaults, path, argv)
        takes_value = _bare(hint) is not bool
        if not has_value:
            if i < len(argv) and not argv[i].startswith("--") and (takes_value or argv[i] in ("true", "false")):
                text, i = argv[i], i + 1
            elif not takes_value:
                text = "true"
            else:
                out.append(f"--{path}")  # argparse says what is missing
                continue
        if path in spelling.members:
            target, entry = spelling.members[path]
            found = lists.setdefault(target, list(_value_at(defaults, target) or ()))
            new = entry(text)
            found[:] = [e for e in found if e.name != new.name] + [new]
            continue
        if path in spelling.joined:
            joined.setdefault(path, []).append(text)
            continue
        if hint is None or path == CONFIG_ARG:
            out.append(f"--{path}={text}")
            continue
        if path in spelling.values and not text.startswith("["):
            value = spelling.values[path](text)
        elif _is_list(hint) or _bare(hint) in (tuple, bool) or (_is_optional(hint) and _bare(hint) is not str):
            value = draccus.decode(hint, draccus.cfgparsing.parse_string(text)) if text.startswith("[") \
                else spelt(text, hint, f"--{path}")
        else:
            out.append(f"--{path}={text}")
            continue
        if _is_list(hint) and path in lists:
            lists[path] += list(value)
        elif _is_list(hint):
            lists[path] = list(value)
        else:
            out.append(f"--{path}={json.dumps(draccus.encode(value))}")
    out += [f"--{path}={json.dumps(draccus.encode(tuple(entries)))}" for path, entries in lists.items()]
    out += [f"--{path}={','.join(t for t in texts if t)}" for path, texts in joined.items()]
    return out


def field_hint(cls: type, defaults: Any, path: str, argv: Sequence[str]) -> Any:
    """The type of the field at ``path`` (``demos.counts``) in ``cls``, None when there is none. A choice field's
    kind is the one ``argv`` picks with ``--group.type=NAME``, else the default's."""
    parts = path.split(".")
    default = defaults
    for depth, part in enumerate(parts):
        if not (isinstance(cls, type) and is_dataclass(cls)):
            return None
        found = {f.name: f for f in fields(cls) if f.init}
        if part not in found:
            return None
        hint = typing.get_type_hints(cls)[part]
        if depth == len(parts) - 1:
            return hint
        default = getattr(default, part, None) if default is not None else None
        prefix = ".".join(parts[: depth + 1])
        chosen = _choice(argv, prefix)
        if chosen is not None and isinstance(hint, type) and issubclass(hint, draccus.ChoiceRegistry):
            try:
                cls, default = hint.get_choice_class(chosen), None
            except KeyError:
                return None
        else:
            cls = type(default) if default is not None and is_dataclass(default) else hint
    return None


def _choice(argv: Sequence[str], prefix: str) -> str | None:
    """The kind ``argv`` picks for the choice field at ``prefix`` (``--policy.type=diffusion``), or None."""
    for k, token in enumerate(argv):
        if token.startswith(f"--{prefix}.type="):
            return token.partition("=")[2]
        if token == f"--{prefix}.type" and k + 1 < len(argv):
            return argv[k + 1]
    return None


def _value_at(obj: Any, path: str) -> Any:
    """The value at ``path`` (``training.steps``) in ``obj``, None where there is none."""
    for part in path.split("."):
        if obj is None or not hasattr(obj, part):
            return None
        obj = getattr(obj, part)
    return obj


def shown(value: Any) -> str:
    """A value as a flag spells it: ``true``, ``none``, lists comma-separated, pairs ``A:B``."""
    value = draccus.encode(value) if is_dataclass(value) or isinstance(value, tuple) else value
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "none"
    if isinstance(value, (list, tuple)) and any("," in str(v) for v in value):
        return json.dumps(value, separators=(",", ":"))  # entries that hold commas: a YAML list
    if isinstance(value, (list, tuple)):
        return ",".join(":".join(map(shown, v)) if isinstance(v, (list, tuple)) else shown(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def _is_optional(hint: Any) -> bool:
    return typing.get_origin(hint) in (types.UnionType, typing.Union) and type(None) in typing.get_args(hint)


def _bare(hint: Any) -> Any:
    """``X`` of ``X | None``; the origin of a generic (``tuple`` of ``tuple[int, ...]``); else ``hint``."""
    if _is_optional(hint):
        (hint,) = [a for a in typing.get_args(hint) if a is not type(None)]
    return typing.get_origin(hint) or hint


def _is_list(hint: Any) -> bool:
    """A ``tuple[X, ...]`` (optional or not)."""
    if _is_optional(hint):
        (hint,) = [a for a in typing.get_args(hint) if a is not type(None)]
    args = typing.get_args(hint)
    return typing.get_origin(hint) is tuple and len(args) == 2 and args[1] is Ellipsis


def spelt(text: str, hint: Any, flag: str) -> Any:
    """``text`` as a value of type ``hint`` in the comma spelling (int, float, str, bool, X | None,
    tuple[X, ...] as ``a,b``, a pair tuple[X, Y] as ``A:B`` or ``A,B``, a list of pairs as ``a:1,b:2``)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if _is_optional(hint):
        if text.lower() in ("none", "null"):
            return None
        (hint,) = [a for a in args if a is not type(None)]
        origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin is tuple and len(args) == 2 and args[1] is Ellipsis:
        return () if text.lower() in ("", "none") else tuple(spelt(t, args[0], flag) for t in text.split(","))
    if origin is tuple:
        parts = text.split(":") if ":" in text else text.split(",")
        if len(parts) != len(args):
            raise ConfigError(f"{flag}: {text!r} is not {':'.join(a.__name__.upper() for a in args)}")
        return tuple(spelt(p, a, flag) for p, a in zip(parts, args, strict=True))
    if hint is bool:
        if text.lower() not in ("true", "false"):
            raise ConfigError(f"{flag}: {text!r}: give true or false")
        return text.lower() == "true"
    if not isinstance(hint, type) or hint not in (int, float, str):
        return draccus.decode(hint, draccus.cfgparsing.parse_string(text))
    try:
        return hint(text)
    except ValueError as err:
        raise ConfigError(f"{flag}: {text!r} is not a valid {hint.__name__}") from err
