"""jaxnet.memo.Memo: the bounded, locked tables jaxnet keeps per process."""

import threading

from jaxnet.memo import Memo


def test_a_full_memo_drops_its_oldest_entry():
    memo = Memo(2)
    memo.put("a", 1)
    memo.put("b", 2)
    memo.put("a", 10)  # an update: nothing dropped
    assert len(memo) == 2 and memo.get("a") == 10
    memo.put("c", 3)
    assert memo.get("a") is None and memo.get("b") == 2 and memo.get("c") == 3
    assert sorted(memo.values()) == [2, 3]
    memo.clear()
    assert len(memo) == 0


def test_get_or_make_makes_once_and_keeps_the_first_made():
    memo, made = Memo(None), []

    def make():
        made.append(1)
        return object()

    first = memo.get_or_make("k", make)
    assert memo.get_or_make("k", make) is first and len(made) == 1
    # threads asking at once all get one value
    seen = []
    threads = [threading.Thread(target=lambda: seen.append(memo.get_or_make("new", make))) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len({id(v) for v in seen}) == 1 and memo.get("new") is seen[0]
