(define (problem blocksworld-p01)
  (:domain blocksworld-4ops)
  (:objects
    b1 b2 b3
  )
  (:init
    (on-table b2)
    (on b1 b2)
    (on b3 b1)
    (clear b3)
    (arm-empty)
  )
  (:goal (and
    (on b1 b2)
    (on b2 b3)
  ))
)
