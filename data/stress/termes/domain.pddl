; Termes: a robot builds structures of stacked blocks on a grid (twostep benchmark data).
; It walks between neighbouring positions whose heights differ by at most one, carries at
; most one block, and gets new blocks from (or returns them to) the depot.
; (succ ?n ?m) means number ?n is one more than number ?m.
(define (domain termes)
  (:requirements :strips :typing :negative-preconditions)
  (:types numb position)
  (:predicates
    (height ?p - position ?h - numb)
    (at ?p - position)
    (has-block)
    (succ ?n - numb ?m - numb)
    (neighbor ?p - position ?q - position)
    (is-depot ?p - position))

  (:action move
    :parameters (?from - position ?to - position ?h - numb)
    :precondition (and (at ?from) (neighbor ?from ?to) (height ?from ?h) (height ?to ?h))
    :effect (and (at ?to) (not (at ?from))))

  (:action move-up
    :parameters (?from - position ?hfrom - numb ?to - position ?hto - numb)
    :precondition (and (at ?from) (neighbor ?from ?to)
                       (height ?from ?hfrom) (height ?to ?hto) (succ ?hto ?hfrom))
    :effect (and (at ?to) (not (at ?from))))

  (:action move-down
    :parameters (?from - position ?hfrom - numb ?to - position ?hto - numb)
    :precondition (and (at ?from) (neighbor ?from ?to)
                       (height ?from ?hfrom) (height ?to ?hto) (succ ?hfrom ?hto))
    :effect (and (at ?to) (not (at ?from))))

  (:action place-block
    :parameters (?rpos - position ?bpos - position ?hbefore - numb ?hafter - numb)
    :precondition (and (at ?rpos) (neighbor ?rpos ?bpos) (height ?rpos ?hbefore)
                       (height ?bpos ?hbefore) (succ ?hafter ?hbefore) (has-block)
                       (not (is-depot ?bpos)))
    :effect (and (height ?bpos ?hafter) (not (height ?bpos ?hbefore)) (not (has-block))))

  (:action remove-block
    :parameters (?rpos - position ?bpos - position ?hbefore - numb ?hafter - numb)
    :precondition (and (at ?rpos) (neighbor ?rpos ?bpos) (height ?rpos ?hafter)
                       (height ?bpos ?hbefore) (succ ?hbefore ?hafter) (not (has-block)))
    :effect (and (height ?bpos ?hafter) (not (height ?bpos ?hbefore)) (has-block)))

  (:action create-block
    :parameters (?p - position)
    :precondition (and (at ?p) (is-depot ?p) (not (has-block)))
    :effect (has-block))

  (:action destroy-block
    :parameters (?p - position)
    :precondition (and (at ?p) (is-depot ?p) (has-block))
    :effect (not (has-block))))
