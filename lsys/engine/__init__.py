"""The derivation engine: ``derive`` (``LSystem``, ``Derivation``: rewriting with context,
queries and the history tree), its compiled kernels (``_derive_kernel``, ``_context_kernel``,
``_branch_cut_kernel``), the ``%`` branch cut (``branch_cut``) and combination modules
(``combination``).  It puts the other rooms to work, so it may import the language, the
interpretation, the history, the architecture, the lsys root modules, ``ramure.grammars``
and ``ramure.<base>``; regeneration and the readers stand on it.
"""
