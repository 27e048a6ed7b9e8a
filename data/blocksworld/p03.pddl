(define (problem blocksworld-p03)
  (:domain blocksworld-4ops)
  (:objects
    b1 b2 b3 b4
  )
  (:init
    (on-table b3)
    (on-table b1)
    (on-table b2)
    (on b4 b2)
    (clear b3)
    (clear b1)
    (clear b4)
    (arm-empty)
  )
  (:goal (and
    (on b1 b2)
    (on b2 b3)
  ))
)
