"""The FE loop of any case (case-independent): an FE-levels model
(:class:`levels.FELevels`, a case supplies its FE model at a joint stiffness), the
causes as FE physics (:mod:`causes`), the one judge's model choice (:mod:`select`),
updating (:mod:`update`, :mod:`assumptions`), the FE-level diagnosis (:mod:`diagnosis`),
the backbone prediction of an estimated joint (:mod:`backbone`). Nothing here knows a
case by name; ``tests/test_fe_loop_case_file.py`` checks that no module imports a case
package."""
