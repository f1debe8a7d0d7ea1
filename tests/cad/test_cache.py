"""The build cache: keyed by parameters and code; a second build reads instead of building."""
import dataclasses

from cad import cache
from cad.cache import ShapeCache, key
from cad.parts.power_mounts import Standoff


def test_key_follows_parameters():
    a = Standoff("orin_standoff", 8.0, 5.0, 3.4)
    assert key(a) == key(Standoff("orin_standoff", 8.0, 5.0, 3.4))
    assert key(a) != key(dataclasses.replace(a, height=5.0000001))


def test_key_follows_code(monkeypatch):
    a = Standoff("orin_standoff", 8.0, 5.0, 3.4)
    before = key(a)
    real = cache._module_source_hash
    monkeypatch.setattr(cache, "_module_source_hash",
                        lambda m: real(m) + ("changed" if m == "cad.parts.power_mounts" else ""))
    assert key(a) != before


def test_second_build_reads_the_cache(tmp_path):
    a = Standoff("orin_standoff", 8.0, 5.0, 3.4)
    c1 = ShapeCache(tmp_path)
    v1 = c1.get(a).Volume()
    assert c1.misses == 1 and list(tmp_path.glob("*.brep"))
    c2 = ShapeCache(tmp_path)
    assert abs(c2.get(a).Volume() - v1) < 1e-9 and c2.hits == 1 and c2.misses == 0
