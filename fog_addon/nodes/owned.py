"""What belongs to the fog: the nodes it adds (by tag, never by name) and data it must not edit.

Every node the fog adds to a user's material, World or light carries the
custom property ``analytic_fog`` (``TAG``), whose value is the node's role
("Surface", "CYCLES Attenuate", "Term 3", ...).  Ownership is decided by
that tag alone, so a user's own node named "AnalyticFog ..." is never taken
for the fog's, and the fog finds its nodes by role even if Blender had to
rename them (a user node already held the name).  The tag is saved with the
file and copied with the node.  The nodes keep readable labels (``AnalyticFog
<role>``) for the artist, and names too, except a material's nodes other than its
``AnalyticFog Surface`` node: renaming a node makes Blender fix every
animation path in the file that could name it, which costs in proportion to
the file's data-blocks (1 000 materials, 64 lights: 1.5-1.9 s of the 20 s that
adding the fog took, growing with the square of the file's size).
"""
import re

PREFIX = "AnalyticFog"   # of the names the fog gives: its nodes and its node groups, images and texts
TAG = "analytic_fog"     # custom property on each node the fog adds: the node's role
BUILT = "analytic_fog_built"   # on the node groups the fog builds: the fingerprint of the code that built them
SUFFIX = re.compile(r"^(?P<base>.+)\.(?P<num>\d{3,})$")   # Blender's ".001" of a clashing name


def base_name(name):
    """``name`` without Blender's ``.NNN`` suffix (an appended or clashing copy's)."""
    m = SUFFIX.match(name)
    return m.group("base") if m else name


def mark(node, role, named=True):
    """Make ``node`` the fog's, with ``role``; label it ``AnalyticFog <role>``, and name it so if ``named``."""
    node[TAG] = role
    node.label = f"{PREFIX} {role}"
    if named:
        node.name = node.label
    return node


def add(tree, bl_idname, role, location, named=True, **props):
    """A new node of the fog's in ``tree`` (see ``mark``) at ``location``, with RNA properties ``props``."""
    n = mark(tree.nodes.new(bl_idname), role, named)
    n.location = location
    for k, v in props.items():
        setattr(n, k, v)
    return n


def is_ours(node):
    return node.get(TAG) is not None


def role_of(node):
    """The fog's role for ``node`` ("" for a user's node)."""
    return node.get(TAG, "")


def find(tree, role):
    """The fog's node with ``role`` in ``tree``, or None."""
    return next((n for n in tree.nodes if n.get(TAG) == role), None)


def is_fogged(idblock):
    """True if the fog added nodes to ``idblock``'s (material, World, light) node tree."""
    return idblock.node_tree is not None and any(is_ours(n) for n in idblock.node_tree.nodes)


def remove_ours(tree):
    """Delete every node the fog added to ``tree`` (and so every link touching them)."""
    for n in [n for n in tree.nodes if is_ours(n)]:
        tree.nodes.remove(n)


def read_only(idblock):
    """Why the fog must not edit ``idblock`` (linked or overridden library data), or None."""
    if idblock.library is not None:
        return f"is linked from the library {idblock.library.name!r}: read-only, left without fog"
    if idblock.override_library is not None:
        return "is a library override: the fog's nodes would not be saved, left without fog (make it local first)"
    return None
