"""The rows of the scene reference (:mod:`masonrydam.scene.reference`, rendered as docs/scene.md): one
:class:`Key` per scene key, grouped in :class:`Section` tables. A module that owns a part of the scene
language (an effect's section, :mod:`masonrydam.effects`) declares its rows with these types beside its
schema fragment, so that the reference and the schema cannot drift."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ABSENT", "REQUIRED", "TIME", "UNIT", "Key", "Marker", "Section", "key"]


class Marker:
    """A default that is not a value: printed as its text in the reference."""

    def __init__(self, text):
        self.text = text

    def __repr__(self):
        return self.text


#: default of a key that must be given
REQUIRED = Marker("required")
#: default of an optional key without a value of its own (left out: the feature is off, or the value is
#: computed; the meaning says which)
ABSENT = Marker("-")

#: ``unit_string`` values: any unit of the key's dimension (``"16.7 GPa"``, ``"10 mm"``, ``"0.3 g"``), or a
#: time in seconds or milliseconds (``"10 ms"``)
UNIT = "yes"
TIME = "s, ms"


@dataclass(frozen=True)
class Key:
    """One scene key.

    path: dotted, ``[]`` for list items, ``<name>`` for user names; type: number, integer, string, bool,
    list or table (or several, "number or string"); unit: SI unit (empty: dimensionless or none);
    unit_string: whether a string with a unit is accepted (:data:`UNIT`, :data:`TIME` or empty);
    default: a value, :data:`REQUIRED` or :data:`ABSENT`; default_text: the default in words, where it is
    computed; choices: the allowed values (the schema's tuple); variants: the values of the section's
    discriminator (``type`` of a stage or load, ``law`` of a material, ``step`` of a processing step,
    the generator) for which the key applies (empty: always); meaning: one line."""

    path: str
    type: str
    meaning: str
    unit: str = ""
    unit_string: str = ""
    default: object = ABSENT
    default_text: str = ""
    choices: tuple | None = None
    variants: tuple = ()


@dataclass(frozen=True)
class Section:
    """One table of the reference: title, a paragraph, the rows; discriminator: the key whose values
    :attr:`Key.variants` lists (shown as the column "For")."""

    title: str
    text: str
    keys: tuple
    discriminator: str = ""


def key(path, type_, meaning, unit="", unit_string="", default=ABSENT, default_text="", choices=None, variants=()):
    """A :class:`Key` (``choices`` and ``variants`` as tuples)."""
    return Key(path, type_, meaning, unit, unit_string, default, default_text,
               None if choices is None else tuple(choices), tuple(variants))
