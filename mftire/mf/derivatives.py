"""Exact derivatives of a model channel with respect to its coefficients (algorithmic, reverse mode).

:func:`jacobian` runs the one model pipeline (:mod:`mftire.mf.solver`) once with the
fitted coefficients replaced by :class:`Var` objects.  A ``Var`` behaves like a numpy
value: every numpy ufunc and ``np.where`` applied to it goes through
``__array_ufunc__`` / ``__array_function__``, computes the value as numpy would, and
records the local derivative of the operation (the chain rule of each elementary
function: d sin x = cos x dx, d atan x = dx / (1 + x²) ...).  A backward sweep then
accumulates the adjoints from the channel back to the coefficients.

Each of the ``n`` outputs depends on its own operating point only (the equations are
elementwise), so an adjoint is an array of ``n`` values, not summed over the points,
and one backward sweep gives every column of the Jacobian: the cost is a few model
evaluations whatever the number of coefficients, against one evaluation per
coefficient for finite differences.  There is no second copy of the equations.

Not differentiable operations (``sign``, comparisons, ``isfinite``) act on the values
and carry no derivative, as the piecewise-constant functions they are; ``abs`` has
derivative ``sign``; ``maximum``/``minimum``/``where`` pass the derivative of the
branch taken.  The extension terms' forms (:data:`mftire.mf.extensions.FORMS`) are written in these
operations too, so that their coefficients are differentiated like the Magic Formula's.

It lives beside the equations (layer 4 of docs/architecture.md), not in the fitting: the equations' own
arithmetic calls into :class:`Var`, so a call path from :mod:`mftire.mf` into it stays in its layer.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

__all__ = ["Var", "jacobian", "seed", "sweep"]


# The binary rules below are _node written out for speed: the same values, the same edges in the
# same order (a before b, non-Var operands left out).  At least one operand is a Var.


def _add(a, b):
    if type(a) is Var:
        if type(b) is Var:
            return Var(a.v + b.v, ((a, 1.0), (b, 1.0)))
        return Var(a.v + b, ((a, 1.0),))
    return Var(a + b.v, ((b, 1.0),))


def _sub(a, b):
    if type(a) is Var:
        if type(b) is Var:
            return Var(a.v - b.v, ((a, 1.0), (b, -1.0)))
        return Var(a.v - b, ((a, 1.0),))
    return Var(a - b.v, ((b, -1.0),))


def _mul(a, b):
    if type(a) is Var:
        av = a.v
        if type(b) is Var:
            bv = b.v
            return Var(av * bv, ((a, bv), (b, av)))
        return Var(av * b, ((a, b),))
    bv = b.v
    return Var(a * bv, ((b, a),))


def _div(a, b):
    if type(b) is Var:
        bv = b.v
        av = a.v if type(a) is Var else a
        v = av / bv
        inv = 1.0 / bv
        if type(a) is Var:
            return Var(v, ((a, inv), (b, -v * inv)))
        return Var(v, ((b, -v * inv),))
    v = a.v / b
    return Var(v, ((a, 1.0 / b),))


def _operators(rule: Callable) -> tuple[Callable, Callable]:
    """The two methods of a binary operator of :class:`Var`: ``rule(self, o)`` and, reflected, ``rule(o, self)``."""
    return (lambda self, o: rule(self, o)), (lambda self, o: rule(o, self))


class Var:
    """A value in the computation graph: ``v`` and the ``(parent, local derivative)`` edges
    (``adj``: the adjoint during the backward sweep of :func:`jacobian`, None otherwise)."""

    __slots__ = ("v", "edges", "adj")
    __array_priority__ = 1000.0

    def __init__(self, v, edges: tuple = ()):
        self.v = v
        self.edges = edges
        self.adj = None

    # Python operators apply the rule of the numpy ufunc directly (what np.add(self, o) would
    # reach through __array_ufunc__, without numpy's dispatch): each binary operator and its
    # reflected form from one rule; the comparisons and the rest through numpy
    __add__, __radd__ = _operators(_add)
    __sub__, __rsub__ = _operators(_sub)
    __mul__, __rmul__ = _operators(_mul)
    __truediv__, __rtruediv__ = _operators(_div)
    __pow__, __rpow__ = _operators(np.power)
    __lt__, __gt__ = _operators(np.less)  # a > b is b < a
    __le__, __ge__ = _operators(np.less_equal)
    __eq__ = _operators(np.equal)[0]  # type: ignore[assignment]
    __ne__ = _operators(np.not_equal)[0]  # type: ignore[assignment]

    def __neg__(self):
        return np.negative(self)

    def __pos__(self):
        return self

    def __abs__(self):
        return np.absolute(self)

    __hash__ = None  # type: ignore[assignment]

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        if method != "__call__" or kwargs:
            return NotImplemented
        rule = _RULES.get(ufunc)
        if rule is not None:
            return rule(*inputs)
        if ufunc in _NO_DERIVATIVE:
            return ufunc(*(_value(x) for x in inputs))
        return NotImplemented

    def __array_function__(self, func, types, args, kwargs):
        if func is np.where and len(args) == 3 and not kwargs:
            cond, a, b = args
            cond = np.asarray(_value(cond), dtype=bool)
            return _node(np.where(cond, _value(a), _value(b)), (a, cond), (b, ~cond))
        if func is np.real:  # the values are real
            return args[0]
        if func in (np.any, np.all, np.ndim, np.shape, np.iscomplexobj, np.isrealobj):
            return func(*(_value(x) for x in args), **kwargs)
        return NotImplemented


def _value(x):
    return x.v if isinstance(x, Var) else x


def _node(v, *edges) -> Var | np.ndarray:
    """A Var with the edges to Var parents (a plain value when none depends on a coefficient)."""
    kept = tuple((x, d) for x, d in edges if isinstance(x, Var))
    return Var(v, kept) if kept else v


def _unary(f: Callable, df: Callable) -> Callable:
    def rule(a: Var):
        v = f(a.v)
        return Var(v, ((a, df(a.v, v)),))

    return rule


def _pow(a, b):
    av, bv = _value(a), _value(b)
    v = av**bv
    da = bv * av ** (bv - 1.0) if isinstance(a, Var) else 0.0
    with np.errstate(all="ignore"):
        db = v * np.log(av) if isinstance(b, Var) else 0.0
    return _node(v, (a, da), (b, db))


def _extreme(pick: Callable) -> Callable:
    def rule(a, b):
        first = np.asarray(pick(_value(a), _value(b)), dtype=bool)
        return _node(np.where(first, _value(a), _value(b)), (a, first), (b, ~first))

    return rule


_RULES: dict = {
    np.add: _add,
    np.subtract: _sub,
    np.multiply: _mul,
    np.true_divide: _div,
    np.power: _pow,
    np.maximum: _extreme(np.greater_equal),
    np.minimum: _extreme(np.less_equal),
    np.negative: lambda a: Var(-a.v, ((a, -1.0),)),
    np.positive: lambda a: a,
    np.sin: _unary(np.sin, lambda x, v: np.cos(x)),
    np.cos: _unary(np.cos, lambda x, v: -np.sin(x)),
    np.tan: _unary(np.tan, lambda x, v: 1.0 + v * v),
    np.arctan: _unary(np.arctan, lambda x, v: 1.0 / (1.0 + x * x)),
    np.arccos: _unary(np.arccos, lambda x, v: -1.0 / np.sqrt(1.0 - x * x)),
    np.sqrt: _unary(np.sqrt, lambda x, v: 0.5 / v),
    np.exp: _unary(np.exp, lambda x, v: v),
    np.log: _unary(np.log, lambda x, v: 1.0 / x),
    np.square: _unary(np.square, lambda x, v: 2.0 * x),
    np.absolute: _unary(np.absolute, lambda x, v: np.sign(x)),
}
_NO_DERIVATIVE = {np.sign, np.less, np.less_equal, np.greater, np.greater_equal, np.equal, np.not_equal,
                  np.isfinite, np.isnan, np.isinf, np.floor, np.ceil, np.round}  # fmt: skip


def seed(q: Mapping[str, float], keys: Sequence[str]) -> tuple[dict, list[Var]]:
    """``q`` with the coefficients ``keys`` replaced by :class:`Var` leaves, and the leaves (for :func:`sweep`):
    evaluate the channel at the returned mapping (under ``np.errstate(all="ignore")``), then sweep."""
    leaves = [Var(float(q[k])) for k in keys]
    qv = dict(q)
    qv.update(zip(keys, leaves, strict=True))
    return qv, leaves


def sweep(out: object, leaves: Sequence[Var], n: int) -> tuple[np.ndarray, np.ndarray]:
    """The channel ``out`` (shape ``(n,)``, computed from a :func:`seed` mapping) and its Jacobian by the
    ``leaves`` (shape ``(n, len(leaves))``): the backward sweep.  Derivatives that are not finite are 0."""
    with np.errstate(all="ignore"):
        jac = np.zeros((n, len(leaves)))
        if not isinstance(out, Var):
            return np.broadcast_to(np.asarray(out, dtype=float), (n,)).copy(), jac
        # topological order (parents before children), iteratively: a depth-first post-order
        order: list[Var] = []
        seen: set[int] = set()
        stack: list = [out, False]  # pairs (node, expanded), flattened
        push, pop, add = order.append, stack.pop, seen.add
        while stack:
            expanded = pop()
            node = pop()
            if expanded:
                push(node)
                continue
            nid = id(node)
            if nid in seen:
                continue
            add(nid)
            stack += (node, True)
            for parent, _ in node.edges:
                if id(parent) not in seen:
                    stack += (parent, False)
        # backward sweep: each node's adjoint is complete when its turn comes (reverse topological order)
        out.adj = 1.0
        try:
            for node in reversed(order):
                edges = node.edges
                if not edges:  # a coefficient: its adjoint is its Jacobian column
                    continue
                a = node.adj
                if a is None:
                    continue
                node.adj = None
                for parent, local in edges:
                    if isinstance(local, float) and local in (1.0, -1.0):
                        contribution = a if local == 1.0 else -a
                    else:
                        contribution = a * local
                    pa = parent.adj
                    parent.adj = contribution if pa is None else pa + contribution
            for j, leaf in enumerate(leaves):
                if leaf.adj is not None:  # a scalar or (n,): numpy broadcasts it into the column
                    jac[:, j] = leaf.adj
        finally:
            for node in order:
                node.adj = None
        value = np.broadcast_to(np.asarray(out.v, dtype=float), (n,)).copy()
    return value, np.where(np.isfinite(jac), jac, 0.0)


def jacobian(
    f: Callable[[Mapping[str, object]], object], q: Mapping[str, float], keys: Sequence[str], n: int
) -> tuple[np.ndarray, np.ndarray]:
    """``f(q)`` (shape ``(n,)``) and its Jacobian ``d f(q) / d q[keys]`` (shape ``(n, len(keys))``).

    ``f`` maps a parameter dictionary to a channel at ``n`` operating points through
    elementwise numpy operations: :func:`seed`, ``f``, :func:`sweep` (a caller in a higher layer
    runs the three itself, so that nothing here calls back up).
    """
    qv, leaves = seed(q, keys)
    with np.errstate(all="ignore"):
        out = f(qv)
    return sweep(out, leaves, n)
