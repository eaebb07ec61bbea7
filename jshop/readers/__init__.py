"""Readers: JSHOP2 and HDDL files into :mod:`htn.jshop.language` objects.

:mod:`.load` chooses the reader by content; :mod:`.jshop2` (grammar
``jshop2.lark``) and :mod:`.hddl` (``hddl.lark``, its model in
:mod:`.hddl_model`, turned into syntax objects by :mod:`.hddl_domain` with
:mod:`.hddl_order` and :mod:`.pullup`) build them; :mod:`.checks` are the
static checks of a domain and a problem."""
