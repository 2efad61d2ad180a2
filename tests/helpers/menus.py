"""What a Blender menu lists, read through its public ``draw``: the menu draws into a stand-in
layout that records the operator ids it is given. Blender's own items need a real window context;
Blender's menu wrapper catches their errors (printing a traceback) and draws the add-ons' items
after them, so the add-ons' items are what the record shows reliably."""
from types import SimpleNamespace


class RecordingLayout:
    operator_context = "INVOKE_REGION_WIN"

    def __init__(self):
        self.operators = []

    def operator(self, idname, **_options):
        self.operators.append(idname)
        return SimpleNamespace()  # the operator's properties, which a menu item may set

    def __getattr__(self, _name):  # separator(), menu(), prop(), ...: nothing to record
        return lambda *_args, **_kwargs: self


def drawn_operators(draw) -> list:
    """The operator ids ``draw(menu, context)`` puts into the menu, in order."""
    layout = RecordingLayout()
    context = SimpleNamespace(workspace=SimpleNamespace(use_filter_by_owner=False))
    draw(SimpleNamespace(layout=layout), context)
    return layout.operators
