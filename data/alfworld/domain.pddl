; A household kitchen in the style of ALFRED / AlfWorld, written for the twostep project.
; Every action names the agent that performs it. Agents stand at locations; each
; receptacle (fridge, drawer, countertop, sink, ...) is reached from one location.
; Small objects lie in or on receptacles, or in an agent's hand.
(define (domain alfworld)
  (:requirements :strips :typing :negative-preconditions)
  (:types
    agent location receptacle item - object)
  (:predicates
    (at ?a - agent ?l - location)              ; where the agent stands
    (handempty ?a - agent)                      ; the agent holds nothing
    (holding ?a - agent ?o - item)              ; the agent carries the item
    (reached-from ?r - receptacle ?l - location) ; the receptacle is within reach from there
    (in ?o - item ?r - receptacle)              ; the item lies in or on the receptacle
    (openable ?r - receptacle)                  ; a door or drawer that can be opened
    (accessible ?r - receptacle)                ; open, or open-topped: its content can be used
    (sink ?r - receptacle)
    (microwave ?r - receptacle)
    (fridge ?r - receptacle)
    (switchable ?r - receptacle)                ; an appliance with a power switch
    (switched-on ?r - receptacle)
    (knife ?o - item)
    (sliceable ?o - item)
    (clean ?o - item)
    (hot ?o - item)
    (cold ?o - item)
    (sliced ?o - item))

  (:action goto
    :parameters (?a - agent ?from - location ?to - location)
    :precondition (at ?a ?from)
    :effect (and (at ?a ?to) (not (at ?a ?from))))

  (:action open
    :parameters (?a - agent ?r - receptacle ?l - location)
    :precondition (and (at ?a ?l) (reached-from ?r ?l) (openable ?r) (not (accessible ?r)))
    :effect (accessible ?r))

  (:action close
    :parameters (?a - agent ?r - receptacle ?l - location)
    :precondition (and (at ?a ?l) (reached-from ?r ?l) (openable ?r) (accessible ?r))
    :effect (not (accessible ?r)))

  (:action pickup
    :parameters (?a - agent ?o - item ?r - receptacle ?l - location)
    :precondition (and (at ?a ?l) (reached-from ?r ?l) (accessible ?r) (in ?o ?r) (handempty ?a))
    :effect (and (holding ?a ?o) (not (in ?o ?r)) (not (handempty ?a))))

  (:action put
    :parameters (?a - agent ?o - item ?r - receptacle ?l - location)
    :precondition (and (at ?a ?l) (reached-from ?r ?l) (accessible ?r) (holding ?a ?o))
    :effect (and (in ?o ?r) (handempty ?a) (not (holding ?a ?o))))

  (:action clean
    :parameters (?a - agent ?o - item ?r - receptacle ?l - location)
    :precondition (and (at ?a ?l) (reached-from ?r ?l) (sink ?r) (holding ?a ?o))
    :effect (clean ?o))

  (:action heat
    :parameters (?a - agent ?o - item ?r - receptacle ?l - location)
    :precondition (and (at ?a ?l) (reached-from ?r ?l) (microwave ?r) (holding ?a ?o))
    :effect (and (hot ?o) (not (cold ?o))))

  (:action cool
    :parameters (?a - agent ?o - item ?r - receptacle ?l - location)
    :precondition (and (at ?a ?l) (reached-from ?r ?l) (fridge ?r) (holding ?a ?o))
    :effect (and (cold ?o) (not (hot ?o))))

  (:action switch-on
    :parameters (?a - agent ?r - receptacle ?l - location)
    :precondition (and (at ?a ?l) (reached-from ?r ?l) (switchable ?r) (not (switched-on ?r)))
    :effect (switched-on ?r))

  (:action switch-off
    :parameters (?a - agent ?r - receptacle ?l - location)
    :precondition (and (at ?a ?l) (reached-from ?r ?l) (switchable ?r) (switched-on ?r))
    :effect (not (switched-on ?r)))

  (:action slice
    :parameters (?a - agent ?o - item ?k - item ?r - receptacle ?l - location)
    :precondition (and (at ?a ?l) (reached-from ?r ?l) (accessible ?r) (in ?o ?r)
                       (sliceable ?o) (knife ?k) (holding ?a ?k))
    :effect (sliced ?o))
)
