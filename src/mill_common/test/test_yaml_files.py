"""yaml_files: users' YAML read safely, every refusal one line (issue 37, point 5)."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import pytest
import yaml
from mill_common.param_sources import params_file_problem
from mill_common.yaml_files import (
    MAX_YAML_BYTES,
    MAX_YAML_DEPTH,
    YamlRefused,
    parse_yaml,
    read_yaml,
    yaml_problem,
)

# The attack of issue 37: nine levels of nine aliases, 9^9 = 387 million strings.
BOMB = 'a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n' + ''.join(
    f'{n}: &{n} [{", ".join([f"*{p}"] * 9)}]\n' for p, n in zip('abcdefgh', 'bcdefghi', strict=True)
)


def _refusal(text: str) -> str:
    with pytest.raises(YamlRefused) as info:
        parse_yaml(text)
    line = yaml_problem(info.value)
    assert '\n' not in line and len(line) < 200
    return line


def test_the_alias_bomb_is_refused_at_its_first_anchor_in_little_memory() -> None:
    assert len(BOMB) < 600
    tracemalloc.start()
    try:
        line = _refusal(BOMB)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert line == 'an anchor (&a) at line 1, column 4: anchors are refused'
    assert peak < 1_000_000  # bytes: nothing was expanded


def test_anchors_and_aliases_are_refused_wherever_they_stand() -> None:
    assert _refusal('x: &v 3\n') == 'an anchor (&v) at line 1, column 4: anchors are refused'
    assert _refusal('x: !!str &v a\n').startswith('an anchor (&v)')
    assert _refusal('- &m {a: 1}\n').startswith('an anchor (&m) at line 1')
    # an alias of an anchor nothing defines: refused as an alias, before PyYAML's own error
    refused = _refusal('x: *nothing\n')
    assert refused == 'an alias (*nothing) at line 1, column 4: aliases are refused'


def test_deep_nesting_is_refused_not_a_recursion_error() -> None:
    assert _refusal('[' * 5000).startswith(f'nested more than {MAX_YAML_DEPTH} levels deep')
    deep = '[' * MAX_YAML_DEPTH + ']' * MAX_YAML_DEPTH
    value = parse_yaml(deep)
    for _ in range(MAX_YAML_DEPTH - 1):
        value = value[0]
    assert value == []


def test_a_file_over_the_limit_is_refused_without_reading_it_all(tmp_path: Path) -> None:
    path = tmp_path / 'big.yaml'
    path.write_text('x: ' + 'a' * MAX_YAML_BYTES + '\n')
    with pytest.raises(YamlRefused, match=r'^larger than 1048576 bytes \(1 MiB\)'):
        read_yaml(path)
    with pytest.raises(YamlRefused, match='larger than'):
        parse_yaml('#' * (MAX_YAML_BYTES + 1))
    just = tmp_path / 'just.yaml'
    just.write_text('x: ' + 'a' * (MAX_YAML_BYTES - 4) + '\n')  # 1 MiB exactly
    assert len(read_yaml(just)['x']) == MAX_YAML_BYTES - 4


def test_plain_yaml_reads_as_the_safe_loader_and_ros_floats_as_rcl() -> None:
    text = 'n:\n  ros__parameters:\n    a: 1.5e9\n    b: [1, 2.0, "y"]\n    c: {d: true}\n'
    assert parse_yaml(text) == yaml.safe_load(text)
    assert parse_yaml(text)['n']['ros__parameters']['a'] == '1.5e9'  # YAML 1.1
    assert parse_yaml(text, ros_floats=True)['n']['ros__parameters']['a'] == 1.5e9


def test_invalid_yaml_is_one_line_with_where() -> None:
    with pytest.raises(yaml.YAMLError) as info:
        parse_yaml('x: [1\n')
    assert yaml_problem(info.value) == (
        "not valid YAML (expected ',' or ']', but got '<stream end>' at line 2, column 1)"
    )


def test_a_nodes_params_file_check_says_the_refusal(tmp_path: Path) -> None:
    bomb = tmp_path / 'bomb.yaml'
    bomb.write_text(BOMB)
    assert params_file_problem(str(bomb)) == (
        'an anchor (&a) at line 1, column 4: anchors are refused'
    )
