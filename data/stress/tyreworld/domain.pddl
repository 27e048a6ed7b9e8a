; Tyreworld: replace flat tyres by intact spares kept in the boot (twostep benchmark data).
; (have ?x) means item ?x is out of the boot, ready to be used. The three tools are
; constants of the domain: every task has one wrench, one jack and one pump, and they
; start in the boot. Nuts are turned only with the wrench out; a hub is lifted only with
; the jack out, and the jack stays under that hub (it is no longer out) until the hub is
; lowered again, so one hub at a time is in the air; a tyre is pumped up only with the
; pump out. No fact belongs to one agent: whoever fetched a tool, anyone may use it.
(define (domain tyreworld)
  (:requirements :strips :typing)
  (:types item container hub - object
          tool wheel nut - item)
  (:constants wrench jack pump - tool)
  (:predicates
    (opened ?c - container)
    (closed ?c - container)
    (unlocked ?c - container)
    (in ?x - item ?c - container)
    (have ?x - item)
    (loose ?n - nut ?h - hub)
    (tight ?n - nut ?h - hub)
    (on-ground ?h - hub)
    (not-on-ground ?h - hub)
    (fastened ?h - hub)
    (unfastened ?h - hub)
    (free ?h - hub)
    (on ?w - wheel ?h - hub)
    (intact ?w - wheel)
    (inflated ?w - wheel)
    (not-inflated ?w - wheel))

  (:action open
    :parameters (?c - container)
    :precondition (and (unlocked ?c) (closed ?c))
    :effect (and (opened ?c) (not (closed ?c))))

  (:action close
    :parameters (?c - container)
    :precondition (opened ?c)
    :effect (and (closed ?c) (not (opened ?c))))

  (:action fetch
    :parameters (?x - item ?c - container)
    :precondition (and (in ?x ?c) (opened ?c))
    :effect (and (have ?x) (not (in ?x ?c))))

  (:action put-away
    :parameters (?x - item ?c - container)
    :precondition (and (have ?x) (opened ?c))
    :effect (and (in ?x ?c) (not (have ?x))))

  (:action loosen
    :parameters (?n - nut ?h - hub)
    :precondition (and (have wrench) (tight ?n ?h) (on-ground ?h))
    :effect (and (loose ?n ?h) (not (tight ?n ?h))))

  (:action tighten
    :parameters (?n - nut ?h - hub)
    :precondition (and (have wrench) (loose ?n ?h) (on-ground ?h))
    :effect (and (tight ?n ?h) (not (loose ?n ?h))))

  (:action jack-up
    :parameters (?h - hub)
    :precondition (and (have jack) (on-ground ?h))
    :effect (and (not-on-ground ?h) (not (on-ground ?h)) (not (have jack))))

  (:action jack-down
    :parameters (?h - hub)
    :precondition (not-on-ground ?h)
    :effect (and (on-ground ?h) (have jack) (not (not-on-ground ?h))))

  (:action undo
    :parameters (?n - nut ?h - hub)
    :precondition (and (have wrench) (not-on-ground ?h) (fastened ?h) (loose ?n ?h))
    :effect (and (have ?n) (unfastened ?h) (not (fastened ?h)) (not (loose ?n ?h))))

  (:action do-up
    :parameters (?n - nut ?h - hub)
    :precondition (and (have wrench) (not-on-ground ?h) (unfastened ?h) (have ?n))
    :effect (and (loose ?n ?h) (fastened ?h) (not (unfastened ?h)) (not (have ?n))))

  (:action remove-wheel
    :parameters (?w - wheel ?h - hub)
    :precondition (and (not-on-ground ?h) (unfastened ?h) (on ?w ?h))
    :effect (and (have ?w) (free ?h) (not (on ?w ?h))))

  (:action put-on-wheel
    :parameters (?w - wheel ?h - hub)
    :precondition (and (not-on-ground ?h) (unfastened ?h) (free ?h) (have ?w))
    :effect (and (on ?w ?h) (not (free ?h)) (not (have ?w))))

  (:action inflate
    :parameters (?w - wheel)
    :precondition (and (have pump) (intact ?w) (not-inflated ?w))
    :effect (and (inflated ?w) (not (not-inflated ?w)))))
