; Several robots, each with a left and a right gripper, carry balls between rooms
; (twostep benchmark data). Balls are plain objects of the root type.
(define (domain gripper-strips)
  (:requirements :strips :typing)
  (:types robot room gripper)
  (:predicates
    (at-robby ?r - robot ?room - room)
    (at ?o - object ?room - room)
    (free ?r - robot ?g - gripper)
    (carry ?r - robot ?o - object ?g - gripper))

  (:action move
    :parameters (?r - robot ?from - room ?to - room)
    :precondition (at-robby ?r ?from)
    :effect (and (at-robby ?r ?to) (not (at-robby ?r ?from))))

  (:action pick
    :parameters (?r - robot ?o - object ?room - room ?g - gripper)
    :precondition (and (at ?o ?room) (at-robby ?r ?room) (free ?r ?g))
    :effect (and (carry ?r ?o ?g) (not (at ?o ?room)) (not (free ?r ?g))))

  (:action drop
    :parameters (?r - robot ?o - object ?room - room ?g - gripper)
    :precondition (and (carry ?r ?o ?g) (at-robby ?r ?room))
    :effect (and (at ?o ?room) (free ?r ?g) (not (carry ?r ?o ?g)))))
