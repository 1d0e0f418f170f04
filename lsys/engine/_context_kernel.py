"""Context neighbours of every module of a string in one linear pass each way (numba).

The left context of a module is found by walking left, skipping ignored
symbols (``#ignore``) and ``[`` (leaving a branch toward its parent) and
jumping over whole ``[ ... ]`` branches; the right context by walking right,
skipping ignored symbols, jumping over lateral branches and stopping at ``]``
(the branch ends).  A walk continues from a found module exactly as it would
start from it, so the k-th context module is :func:`neighbours` applied k
times, and each walk is memoised over the string: linear, whatever the
branching (a walk over 20,000 sibling branches is one jump per branch, once).
"""

from __future__ import annotations

import numpy as np

from ramure.jit import njit


@njit(cache=True, nogil=True)
def neighbours(symbols, match, open_id, close_id, ignored):
    """(prev, next): the nearest left / right context module of each position, -1 for none.

    ``match`` are the bracket matches (-1: unmatched); ``ignored`` a boolean
    table by symbol id; ``open_id``/``close_id`` -1 when the grammar has no brackets.
    """
    n = len(symbols)
    # reach_left[j]: the context module found walking left from j inclusive (-1: none).
    reach_left = np.empty(n, np.int64)
    for j in range(n):
        s = symbols[j]
        if s == close_id:
            m = match[j]
            reach_left[j] = reach_left[m - 1] if m > 0 else -1
        elif s == open_id or ignored[s]:
            reach_left[j] = reach_left[j - 1] if j > 0 else -1
        else:
            reach_left[j] = j
    reach_right = np.empty(n, np.int64)
    for j in range(n - 1, -1, -1):
        s = symbols[j]
        if s == open_id:
            m = match[j]
            reach_right[j] = reach_right[m + 1] if 0 <= m < n - 1 else -1
        elif s == close_id:
            reach_right[j] = -1
        elif ignored[s]:
            reach_right[j] = reach_right[j + 1] if j < n - 1 else -1
        else:
            reach_right[j] = j
    prev = np.empty(n, np.int64)
    nxt = np.empty(n, np.int64)
    for i in range(n):
        prev[i] = reach_left[i - 1] if i > 0 else -1
        nxt[i] = reach_right[i + 1] if i < n - 1 else -1
    return prev, nxt


@njit(cache=True, nogil=True)
def match_contexts(cand, prev, nxt, symbols, nparams, want_sym, want_arity, sides):
    """Which candidates have the wanted context; returns (ok, found).

    ``want_sym``/``want_arity``/``sides`` describe the context modules in walk
    order: the left context nearest first (side -1), then the right context
    nearest first (side +1); -1 in ``want_sym``/``want_arity`` matches any
    symbol / arity.  ``found[k, c]`` is the string position of candidate c's
    k-th context module (-1 where it does not match).
    """
    m = len(want_sym)
    found = np.full((m, len(cand)), -1, np.int64)
    ok = np.ones(len(cand), np.bool_)
    for c in range(len(cand)):
        left = right = cand[c]
        for k in range(m):
            if sides[k] < 0:
                left = prev[left]
                at = left
            else:
                right = nxt[right]
                at = right
            if (
                at < 0
                or (want_sym[k] >= 0 and symbols[at] != want_sym[k])
                or (want_arity[k] >= 0 and nparams[at] != want_arity[k])
            ):
                ok[c] = False
                break
            found[k, c] = at
    return ok, found


@njit(cache=True, nogil=True)
def choose_first_match(
    symbols,
    nparams,
    free,
    chosen,
    reach_left,
    reach_right,
    symbol_start,
    symbol_groups,
    group_arity,
    group_rule,
    context_start,
    want_sym,
    want_arity,
    sides,
):
    """Give each free, unchosen module the rule of the first group it matches (one pass).

    For groups that take every match (deterministic, first rule without a
    condition), this is the same as matching them one after another.
    ``symbol_groups[symbol_start[s]:symbol_start[s + 1]]`` are the groups (in
    order) whose predecessor is symbol s; group g wants arity
    ``group_arity[g]`` and the context modules ``context_start[g]`` to
    ``context_start[g + 1]`` of ``want_sym``/``want_arity``/``sides`` (as in
    :func:`match_contexts`), walked with :func:`reach`'s arrays.  Writes ``chosen`` in place.
    """
    top = len(symbol_start) - 1
    last = len(symbols) - 1
    for i in range(len(symbols)):
        if chosen[i] >= 0 or not free[i]:
            continue
        s = symbols[i]
        if s >= top:
            continue
        for q in range(symbol_start[s], symbol_start[s + 1]):
            g = symbol_groups[q]
            if nparams[i] != group_arity[g]:
                continue
            left = i
            right = i
            ok = True
            for c in range(context_start[g], context_start[g + 1]):
                if sides[c] < 0:
                    left = reach_left[left - 1] if left > 0 else -1
                    at = left
                else:
                    right = reach_right[right + 1] if 0 <= right < last else -1
                    at = right
                if (
                    at < 0
                    or (want_sym[c] >= 0 and symbols[at] != want_sym[c])
                    or (want_arity[c] >= 0 and nparams[at] != want_arity[c])
                ):
                    ok = False
                    break
            if ok:
                chosen[i] = group_rule[g]
                break


@njit(cache=True, nogil=True)
def reach(symbols, open_id, close_id, ignored):
    """(reach_left, reach_right) as int32: the context module found walking left / right
    from each position inclusive (-1: none); :func:`neighbours` without its bracket
    matches, which are found here with a stack (a ``]`` closes the nearest open ``[``).

    Module i's left neighbour is ``reach_left[i - 1]`` and its right one
    ``reach_right[i + 1]`` (-1 past the ends).
    """
    n = len(symbols)
    reach_left = np.empty(n, np.int32)
    stack = np.empty(n + 1, np.int32)
    top = 0
    for j in range(n):
        s = symbols[j]
        if s == close_id and top > 0:
            top -= 1
            m = stack[top]
            reach_left[j] = reach_left[m - 1] if m > 0 else -1
        elif s == close_id:  # unmatched: as before, nothing to its left is reachable
            reach_left[j] = -1
        elif s == open_id:
            stack[top] = j
            top += 1
            reach_left[j] = reach_left[j - 1] if j > 0 else -1
        elif ignored[s]:
            reach_left[j] = reach_left[j - 1] if j > 0 else -1
        else:
            reach_left[j] = j
    reach_right = np.empty(n, np.int32)
    top = 0
    for j in range(n - 1, -1, -1):
        s = symbols[j]
        if s == open_id and top > 0:
            top -= 1
            m = stack[top]
            reach_right[j] = reach_right[m + 1] if m < n - 1 else -1
        elif s == open_id:
            reach_right[j] = -1
        elif s == close_id:
            stack[top] = j
            top += 1
            reach_right[j] = -1
        elif ignored[s]:
            reach_right[j] = reach_right[j + 1] if j < n - 1 else -1
        else:
            reach_right[j] = j
    return reach_left, reach_right
