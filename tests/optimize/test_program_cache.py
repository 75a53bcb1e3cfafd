"""The programs' LRU cache (ocp.optimize.program_cache): hits, eviction order, build notices."""

from ocp.optimize.program_cache import ProgramCache


def test_least_recently_used_is_evicted_and_builds_are_heard() -> None:
    cache: ProgramCache[str] = ProgramCache(2)
    builds: list[str] = []
    heard: list[str] = []

    def get(key: str) -> bool:
        def build() -> str:
            builds.append(key)
            return key.upper()
        prog, built = cache.get(key, build, heard.append)
        assert prog == key.upper()
        return built

    assert get("a") and get("b")
    assert not get("a")  # a hit: "a" is now the most recently used
    assert get("c")  # evicts "b", the least recently used
    assert not get("a") and get("b")  # "a" survived; "b" is built again (evicting "c")
    assert builds == ["a", "b", "c", "b"] and heard == ["build", "built"] * 4
    cache.clear()
    assert get("a")
