"""The coffee robot of issue 19 (3 operators, 2 methods), in JSHOP2 and HDDL:
a newcomer's first domain, the one docs/guide.md writes (tests/e2e/test_guide.py
checks that its copy is this one)."""

COFFEE = """\
; A coffee robot: it goes to the kitchen, brews a cup and brings it to a person.
(defdomain coffee (
  (:operator (!goto ?robot ?from ?to)
    ((at ?robot ?from))
    ((at ?robot ?from))
    ((at ?robot ?to)))

  (:operator (!brew ?robot ?cup)
    ((at ?robot kitchen) (empty ?cup))
    ((empty ?cup))
    ((full ?cup) (holding ?robot ?cup)))

  (:operator (!hand ?robot ?cup ?person)
    ((holding ?robot ?cup) (at ?robot ?place) (at ?person ?place))
    ((holding ?robot ?cup))
    ((has ?person ?cup)))

  (:method (go ?robot ?to)
    already-there ((at ?robot ?to)) ()
    drive ((at ?robot ?from)) ((!goto ?robot ?from ?to)))

  (:method (serve ?robot ?person)
    ((empty ?cup) (at ?person ?place))
    ((go ?robot kitchen) (!brew ?robot ?cup) (go ?robot ?place) (!hand ?robot ?cup ?person)))))
"""
MORNING = """\
(defproblem morning coffee
  ((at robby dock) (empty mug) (at ada office))
  ((serve robby ada)))
"""

COFFEE_HDDL = """\
(define (domain coffee)
  (:requirements :typing :hierarchy)
  (:types robot place cup person - object)
  (:constants kitchen - place)
  (:predicates (at ?x - object ?p - place) (empty ?c - cup) (holding ?r - robot ?c - cup)
               (has ?who - person ?c - cup))
  (:task go :parameters (?r - robot ?to - place))
  (:task serve :parameters (?r - robot ?who - person))
  (:action goto
    :parameters (?r - robot ?from ?to - place)
    :precondition (at ?r ?from)
    :effect (and (not (at ?r ?from)) (at ?r ?to)))
  (:action brew
    :parameters (?r - robot ?c - cup)
    :precondition (and (at ?r kitchen) (empty ?c))
    :effect (and (not (empty ?c)) (holding ?r ?c)))
  (:action hand
    :parameters (?r - robot ?c - cup ?who - person ?p - place)
    :precondition (and (holding ?r ?c) (at ?r ?p) (at ?who ?p))
    :effect (and (not (holding ?r ?c)) (has ?who ?c)))
  (:method already-there
    :parameters (?r - robot ?to - place)
    :task (go ?r ?to)
    :precondition (at ?r ?to)
    :ordered-subtasks ())
  (:method drive
    :parameters (?r - robot ?from ?to - place)
    :task (go ?r ?to)
    :precondition (at ?r ?from)
    :ordered-subtasks (goto ?r ?from ?to))
  (:method serve-coffee
    :parameters (?r - robot ?who - person ?c - cup ?p - place)
    :task (serve ?r ?who)
    :precondition (and (empty ?c) (at ?who ?p))
    :ordered-subtasks (and (go ?r kitchen) (brew ?r ?c) (go ?r ?p) (hand ?r ?c ?who ?p))))
"""
MORNING_HDDL = """\
(define (problem morning) (:domain coffee)
  (:objects robby - robot dock office - place mug - cup ada - person)
  (:htn :ordered-subtasks (serve robby ada))
  (:init (at robby dock) (empty mug) (at ada office)))
"""
