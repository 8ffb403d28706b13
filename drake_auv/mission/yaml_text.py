"""Reading a mission's YAML (the file and `--set` values): PyYAML's safe loader with numbers
read as YAML 1.2 reads them.

PyYAML follows YAML 1.1, where a float needs a dot and a signed exponent: `1.0e9` and `1e9`
would be strings, and a mission key would be refused as "not a number". `MissionLoader` also
reads `[-+]d[.d]e[-+]d` and `[-+].de[-+]d` (exponent sign optional) as floats; everything else
is the safe loader's.
"""

from __future__ import annotations

import re

import yaml


class MissionLoader(yaml.SafeLoader):
    """`yaml.SafeLoader` with YAML 1.2's exponent floats (`1.0e9`, `1e9`, `-2.5E-3`)."""


MissionLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$"),
    list("-+0123456789."))


def load_yaml(text: str):
    """The YAML document `text` as plain Python values (`MissionLoader`)."""
    return yaml.load(text, Loader=MissionLoader)  # noqa: S506 (a SafeLoader)
