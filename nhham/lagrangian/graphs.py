"""The graphs of an analysis as plain data (DESIGN.md §4).

Two graphs appear in every classification: the provenance of the constraints (which
constraint generated which, stage by stage) and the blocks of a matrix (W, C, the
bracket matrix B: the connected components of its nonzero pattern). Neither needs a
graph library while the analysis runs, and importing networkx costs a quarter of a
second of a command's start-up. So the provenance is recorded as nodes and edges
(:class:`Provenance`) and turned into a ``networkx.DiGraph`` only when someone asks for
it (:meth:`Provenance.graph`, networkx imported then), and the blocks come from a
union-find (:func:`connected_components`).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Hashable, Iterable

__all__ = ["Provenance", "connected_components"]


def connected_components(nodes: Iterable[Hashable],
                         edges: Iterable[tuple[Hashable, Hashable]]) -> list[list]:
    """The connected components of an undirected graph, each in the order of ``nodes``.

    Parameters
    ----------
    nodes : iterable of hashable
        Every node (isolated ones included), in the order the components keep.
    edges : iterable of pairs
        Undirected edges between nodes of ``nodes``.

    Returns
    -------
    list of list
        One list per component, its nodes in the order of ``nodes``; the components in
        the order of their first node.

    Examples
    --------
    >>> connected_components(range(5), [(0, 3), (2, 1)])
    [[0, 3], [1, 2], [4]]
    """
    order = list(dict.fromkeys(nodes))
    parent = {node: node for node in order}

    def root(node):
        while parent[node] != node:
            parent[node] = parent[parent[node]]     # path halving
            node = parent[node]
        return node

    for a, b in edges:
        ra, rb = root(a), root(b)
        if ra != rb:
            parent[rb] = ra
    groups: dict = {}
    for node in order:
        groups.setdefault(root(node), []).append(node)
    return list(groups.values())


@dataclass(frozen=True)
class Provenance:
    """The provenance graph of a run as data: nodes and directed edges with attributes.

    Attributes
    ----------
    nodes : tuple of (label, mapping)
        Constraint labels with their attributes (``expr``, ``stage``, ``kind``, ...), in
        the order they were added.
    edges : tuple of (source, target, mapping)
        ``source -> target`` when the condition that produced ``target`` involves the
        tangency equation of ``source`` (attributes ``stage``, ``label``).

    Examples
    --------
    >>> p = Provenance().with_node("constraints[0]", stage=1, kind="primary")
    >>> p = p.with_node("secondary[0]", stage=2, kind="secondary")
    >>> p = p.with_edge("constraints[0]", "secondary[0]", stage=1)
    >>> p.labels(kind="secondary")
    ('secondary[0]',)
    >>> G = p.graph()
    >>> list(G.edges(data=True))
    [('constraints[0]', 'secondary[0]', {'stage': 1})]
    """

    nodes: tuple = ()
    edges: tuple = ()

    def with_node(self, label: str, **attributes) -> Provenance:
        """This provenance with one more node."""
        return Provenance(self.nodes + ((label, MappingProxyType(attributes)),), self.edges)

    def with_edge(self, source: str, target: str, **attributes) -> Provenance:
        """This provenance with one more edge ``source -> target``."""
        return Provenance(self.nodes,
                          self.edges + ((source, target, MappingProxyType(attributes)),))

    def has_node(self, label: str) -> bool:
        """Whether ``label`` is a node (added as one, or the end of an edge)."""
        return label in self._labels()

    def labels(self, kind: str | None = None) -> tuple:
        """The node labels in order (those whose ``kind`` attribute is ``kind``)."""
        attrs = self._attributes()
        return tuple(lab for lab in self._labels()
                     if kind is None or attrs.get(lab, {}).get("kind") == kind)

    def with_attribute(self, name: str, value) -> Provenance:
        """Every node (the ends of edges too) with the attribute ``name = value``."""
        attrs = self._attributes()
        nodes = tuple((lab, MappingProxyType({**attrs.get(lab, {}), name: value}))
                      for lab in self._labels())
        return Provenance(nodes, self.edges)

    @staticmethod
    def union(parts: Iterable[Provenance]) -> Provenance:
        """The provenance of several runs together (nodes, then edges, in run order)."""
        parts = list(parts)
        return Provenance(sum((p.nodes for p in parts), ()), sum((p.edges for p in parts), ()))

    def graph(self):
        """A new ``networkx.DiGraph`` of these nodes and edges (networkx imported here)."""
        import networkx as nx

        graph = nx.DiGraph()
        graph.add_nodes_from((lab, dict(attrs)) for lab, attrs in self.nodes)
        graph.add_edges_from((a, b, dict(attrs)) for a, b, attrs in self.edges)
        return graph

    def _labels(self) -> list:
        """Labels in the order a DiGraph built from nodes, then edges, lists them."""
        return list(dict.fromkeys([lab for lab, _ in self.nodes]
                                  + [x for a, b, _ in self.edges for x in (a, b)]))

    def _attributes(self) -> dict:
        out: dict = {}
        for lab, attrs in self.nodes:
            out.setdefault(lab, {}).update(attrs)
        return out
