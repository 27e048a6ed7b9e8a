; Tyreworld: replace flat tyres by intact spares kept in the boot (twostep benchmark data).
; Tools (wrench, jack, pump) are objects of the world but no action needs them in hand,
; so no fact belongs to an agent: every fact is shared by whoever works on the car.
; (have ?x) means item ?x lies out, ready to be used.
(define (domain tyreworld)
  (:requirements :strips :typing)
  (:types item container hub - object
          tool wheel nut - item)
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
    :precondition (and (tight ?n ?h) (on-ground ?h))
    :effect (and (loose ?n ?h) (not (tight ?n ?h))))

  (:action tighten
    :parameters (?n - nut ?h - hub)
    :precondition (and (loose ?n ?h) (on-ground ?h))
    :effect (and (tight ?n ?h) (not (loose ?n ?h))))

  (:action jack-up
    :parameters (?h - hub)
    :precondition (on-ground ?h)
    :effect (and (not-on-ground ?h) (not (on-ground ?h))))

  (:action jack-down
    :parameters (?h - hub)
    :precondition (not-on-ground ?h)
    :effect (and (on-ground ?h) (not (not-on-ground ?h))))

  (:action undo
    :parameters (?n - nut ?h - hub)
    :precondition (and (not-on-ground ?h) (fastened ?h) (loose ?n ?h))
    :effect (and (have ?n) (unfastened ?h) (not (fastened ?h)) (not (loose ?n ?h))))

  (:action do-up
    :parameters (?n - nut ?h - hub)
    :precondition (and (not-on-ground ?h) (unfastened ?h) (have ?n))
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
    :precondition (and (intact ?w) (not-inflated ?w))
    :effect (and (inflated ?w) (not (not-inflated ?w)))))
