"""Reading a mission's YAML (the file and `--set` values): PyYAML's safe loader with numbers
read as YAML 1.2 reads them.

PyYAML follows YAML 1.1, where a float needs a dot and a signed exponent: `1.0e9` and `1e9`
would be strings, and a mission key would be refused as "not a number". `MissionLoader` also
reads `[-+]d[.d]e[-+]d` and `[-+].de[-+]d` (exponent sign optional) as floats; everything else
is the safe loader's.

A document is bounded before it is built: at most `MAX_BYTES` of text and `MAX_VALUES` values
once its aliases are expanded (counted on the composed node graph, each shared node once per
use, in time proportional to the distinct nodes), so an alias bomb (`&a [x, x, ...]`, `&b [*a,
*a, ...]`, ...) or a recursive alias is refused at once, before anything reads the values.
"""

from __future__ import annotations

import re
from pathlib import Path

import yaml

MAX_BYTES = 1 << 20  # a mission file's text
MAX_VALUES = 100_000  # scalars, lists and mappings, aliases expanded


class YamlLimitError(yaml.YAMLError):
    """A document over `MAX_BYTES` or `MAX_VALUES`; the message names the figure and limit."""


class MissionLoader(yaml.SafeLoader):
    """`yaml.SafeLoader` with YAML 1.2's exponent floats (`1.0e9`, `1e9`, `-2.5E-3`)."""


MissionLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$"),
    list("-+0123456789."))


def load_yaml(text: str):
    """The YAML document `text` as plain Python values (`MissionLoader`); `YamlLimitError` past
    the limits (see the module), `yaml.YAMLError` when it is not YAML."""
    if len(text) > MAX_BYTES:
        raise YamlLimitError(f"holds {len(text)} characters, more than {MAX_BYTES}")
    loader = MissionLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        values = _expanded_size(node)
        if values > MAX_VALUES:
            raise YamlLimitError(f"expands to more than {MAX_VALUES} values through its aliases "
                                 f"(&anchor / *alias): {values}")
        return loader.construct_document(node)
    finally:
        loader.dispose()


def load_yaml_file(path):
    """`load_yaml` of file `path`, its size checked before it is read."""
    size = Path(path).stat().st_size
    if size > MAX_BYTES:
        raise YamlLimitError(f"is {size} bytes, more than {MAX_BYTES}")
    return load_yaml(Path(path).read_text())


def _expanded_size(root: yaml.Node) -> int:
    """The number of values `root` stands for, every alias expanded; more than `MAX_VALUES`
    (counting stops there) for a node that contains itself."""
    sizes, busy = {}, set()

    def size(node) -> int:
        key = id(node)
        if key in sizes:
            return sizes[key]
        if key in busy:  # a recursive alias: infinite once expanded
            return MAX_VALUES + 1
        busy.add(key)
        total = 1
        if isinstance(node, yaml.SequenceNode):
            children = node.value
        elif isinstance(node, yaml.MappingNode):
            children = [item for pair in node.value for item in pair]
        else:
            children = []
        for child in children:
            total = min(total + size(child), MAX_VALUES + 1)
        busy.discard(key)
        sizes[key] = total
        return total

    return size(root)
