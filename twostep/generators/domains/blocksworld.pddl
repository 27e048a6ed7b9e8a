; Blocksworld with one arm and four operators (twostep benchmark data). Untyped and named
; blocksworld-4ops, as in the paper's task files, so that those files read with it as they are.
(define (domain blocksworld-4ops)
  (:requirements :strips)
  (:predicates
    (on ?top ?below)
    (on-table ?b)
    (clear ?b)
    (arm-empty)
    (holding ?b))

  (:action pickup
    :parameters (?b)
    :precondition (and (clear ?b) (on-table ?b) (arm-empty))
    :effect (and (holding ?b)
                 (not (clear ?b)) (not (on-table ?b)) (not (arm-empty))))

  (:action putdown
    :parameters (?b)
    :precondition (holding ?b)
    :effect (and (on-table ?b) (clear ?b) (arm-empty)
                 (not (holding ?b))))

  (:action stack
    :parameters (?b ?target)
    :precondition (and (holding ?b) (clear ?target))
    :effect (and (on ?b ?target) (clear ?b) (arm-empty)
                 (not (holding ?b)) (not (clear ?target))))

  (:action unstack
    :parameters (?b ?below)
    :precondition (and (on ?b ?below) (clear ?b) (arm-empty))
    :effect (and (holding ?b) (clear ?below)
                 (not (on ?b ?below)) (not (clear ?b)) (not (arm-empty)))))
