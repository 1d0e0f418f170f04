"""The derivation-history tree: ``tree`` (``DerivationTree``, its arrays and leaf sums, with
the compiled ``_tree_kernel``) and ``decompose`` (decomposition rules applied to a tree
section).  It is the data structure every other room reads, so it may import only the lsys
root modules and ``ramure.<base>``.
"""
